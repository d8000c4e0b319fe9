"""The output folder of a batch: per-model files, ``results.jsonl``, ``summary.csv`` and the
``summary.html`` contact sheet.

Layout of ``--out DIR``::

    results.jsonl        one line per model, appended (and flushed) as each model finishes
    summary.csv          model, faces, bones, max stress MPa, ratio, weak bones, flags, status, seconds
    summary.html         contact sheet: stress picture + key numbers, weakest first, sortable
    models/ID.json       the full report of each model (analyze --json schema + batch fields)
    models/ID.png        its stress picture
    models/ID_corrected.EXT   the corrected mesh (with correction on)

A line in ``results.jsonl`` is written after the model's own files, so a line means the model is
done; ``--resume`` skips the models it lists.
"""

from __future__ import annotations

import csv
import html
import io
import json
import os
import re
from pathlib import Path

from ..io.atomic import write_atomic
from ..io.model import printable
from ..report import finite, to_json
from .task import summary_line

RESULTS = "results.jsonl"
#: the settings of the run that made the folder (``--resume`` checks it)
SETTINGS_FILE = "batch_settings.json"
#: settings that change no result (``--resume`` may change them)
_RESUME_FREE = ("png", "png_dpi", "engine_threads", "model_timeout_s", "max_sections")


def _result_settings(s) -> dict:
    d = s.as_dict()
    return {k: v for k, v in d.items() if k not in _RESUME_FREE}


def check_resume_settings(out, s) -> None:
    """Raise ValueError when ``--resume`` would mix results of other settings into ``out``
    (the first run's settings are in ``out/batch_settings.json``). Decided: refuse, naming
    what differs; a run with new settings goes to a new folder (or runs without --resume)."""
    path = Path(out) / SETTINGS_FILE
    if not path.is_file():
        return
    try:
        old = json.loads(path.read_text(encoding="utf-8"))
    except (OSError, ValueError):
        return
    new = json.loads(json.dumps(_result_settings(s)))
    diff = []
    for k in sorted(set(old) | set(new)):
        a, b = old.get(k), new.get(k)
        if isinstance(a, dict) and isinstance(b, dict):
            diff += [f"{k2} {a.get(k2)!r} -> {b.get(k2)!r}" for k2 in sorted(set(a) | set(b))
                     if a.get(k2) != b.get(k2)]
        elif a != b:
            diff.append(f"{k} {a!r} -> {b!r}")
    if diff:
        raise ValueError(f"--resume: {out} was made with other settings ({'; '.join(diff[:6])}); "
                         "run without --resume to start over, or use another --out")


def save_settings(out, s) -> None:
    write_atomic(Path(out) / SETTINGS_FILE, json.dumps(_result_settings(s), indent=1,
                                                       sort_keys=True) + "\n")
MODELS_DIR = "models"


def _clean(x):
    """JSON-safe copy: non-finite floats become None (the report's finite-number rule)."""
    if isinstance(x, float):
        return finite(x)
    if isinstance(x, dict):
        return {k: _clean(v) for k, v in x.items()}
    if isinstance(x, (list, tuple)):
        return [_clean(v) for v in x]
    return x


def _printable(x):
    """Copy with every str UTF-8 encodable (a non-UTF-8 file name's bytes shown as U+FFFD):
    for the files people open (JSON report, CSV, HTML). ``results.jsonl`` keeps the exact
    path (JSON escapes it), which ``--resume`` matches."""
    if isinstance(x, str):
        return printable(x)
    if isinstance(x, dict):
        return {printable(k) if isinstance(k, str) else k: _printable(v) for k, v in x.items()}
    if isinstance(x, (list, tuple)):
        return [_printable(v) for v in x]
    return x


def read_results(out) -> list[dict]:
    """The complete lines of ``out/results.jsonl`` (a torn last line is ignored); the last line
    of a model wins when it appears twice."""
    path = Path(out) / RESULTS
    if not path.is_file():
        return []
    by_model: dict[str, dict] = {}
    with open(path, encoding="utf-8") as fh:
        for line in fh:
            if not line.endswith("\n"):
                break  # torn by a kill in the middle of a write
            try:
                rec = json.loads(line)
            except json.JSONDecodeError:
                continue
            if isinstance(rec, dict) and "model" in rec:
                by_model[rec["model"]] = rec
    return list(by_model.values())


def repair_results(out) -> None:
    """Cut a torn last line of ``results.jsonl`` (the run was killed while writing it)."""
    path = Path(out) / RESULTS
    if not path.is_file():
        return
    data = path.read_bytes()
    if data and not data.endswith(b"\n"):
        keep = data.rfind(b"\n") + 1
        with open(path, "r+b") as fh:
            fh.truncate(keep)


_FINISHED = "_finished"
#: in JSON text (ASCII: json.dumps escapes the rest): a UTF-16 surrogate, which a name that is
#: not UTF-8 (a file name's undecodable bytes) leaves as a lone escape
_SURROGATE = re.compile(r"\\ud[89a-f]", re.IGNORECASE)


def _json_of(record: dict, report: bool) -> tuple[dict, str | None]:
    """(the record JSON-safe, the text of its report when ``report``). The fast path writes the
    record once (the common case: every number finite, every name UTF-8); otherwise it is made
    JSON-safe first (:func:`_clean`, :func:`_printable`): the same text either way."""
    try:
        text = to_json(record) if report else None
        if text is None:
            json.dumps(record, allow_nan=False)
            return record, None
    except ValueError:  # a non-finite number
        record = _clean(record)
        text = to_json(_printable(record)) if report else None
        return record, text
    if _SURROGATE.search(text):  # rare: a surrogate pair or a name that is not UTF-8
        text = to_json(_printable(record))
    return record, text


def finish_record(record: dict) -> dict:
    """A task's record as the output folder keeps it: JSON-safe (non-finite numbers None) and,
    for an analysed model, ``json`` naming its report, whose bytes (``models/ID.json``) join
    the record's ``_files``. Made where the model was analysed (a pool or Dask worker), so that
    the workers serialise the reports in parallel and the batch process only writes bytes."""
    files = dict(record.pop("_files", None) or {})
    ok = record.get("status") == "ok"
    if ok:
        record["json"] = f"{MODELS_DIR}/{record['id']}.json"
    rec, text = _json_of(record, ok)
    if ok:
        files[f"{rec['id']}.json"] = text.encode("utf-8")
    rec["_files"] = files
    rec[_FINISHED] = True
    return rec


class OutputWriter:
    """Writes each finished model's files and its ``results.jsonl`` line."""

    def __init__(self, out, resume: bool = False):
        self.out = Path(out)
        self.models = self.out / MODELS_DIR
        self.models.mkdir(parents=True, exist_ok=True)
        if resume:
            repair_results(self.out)
        mode = "a" if resume else "w"
        self._fh = open(self.out / RESULTS, mode, encoding="utf-8")  # noqa: SIM115

    def write(self, record: dict) -> dict:
        """Write the model's files and append its line; returns the record without file bytes."""
        rec = record if record.get(_FINISHED) else finish_record(record)
        rec.pop(_FINISHED, None)
        files = rec.pop("_files", None) or {}
        for name, data in files.items():  # the report last: written means the model is done
            write_atomic(self.models / name, data)
        self._fh.write(json.dumps(summary_line(rec), allow_nan=False) + "\n")
        self._fh.flush()
        return rec

    def close(self):
        self._fh.close()


CSV_COLUMNS = [
    ("model", "model"),
    ("faces", "faces"),
    ("bones", "bone_count"),
    ("max_stress_mpa", "max_stress_mpa"),
    ("ratio", "stress_ratio"),
    ("weak_bones", "weak_bones"),
    ("flags", "flags"),
    ("status", "status"),
    ("seconds", "seconds"),
]


def _order(records):
    """Weakest first (highest stress ratio); models without a ratio (skipped, failed) last."""
    return sorted(
        records,
        key=lambda r: (r.get("stress_ratio") is None, -(r.get("stress_ratio") or 0.0), r.get("model", "")),
    )


def _weak_names(r) -> str:
    return " ".join(w["bone"] for w in r.get("weak_bones") or [])


def _status_text(r) -> str:
    return r["status"] if not r.get("reason") else f"{r['status']}: {r['reason']}"


def write_csv(out, records) -> Path:
    path = Path(out) / "summary.csv"
    fh = io.StringIO(newline="")
    w = csv.writer(fh)
    w.writerow([c for c, _ in CSV_COLUMNS])
    for r in _order(_printable(records)):
        row = []
        for col, key in CSV_COLUMNS:
            v = r.get(key)
            if col == "weak_bones":
                v = _weak_names(r)
            elif col == "flags":
                v = ";".join(v or [])
            elif col == "status":
                v = _status_text(r)
            elif isinstance(v, float):
                v = f"{v:.6g}"
            row.append("" if v is None else v)
        w.writerow(row)
    write_atomic(path, fh.getvalue())
    return path


_JS = """
document.querySelectorAll('th[data-k]').forEach(function (th) {
  th.addEventListener('click', function () {
    var tb = document.querySelector('tbody'), k = th.dataset.k, num = th.dataset.num;
    var up = th.dataset.dir !== 'asc'; th.dataset.dir = up ? 'asc' : 'desc';
    var rows = Array.prototype.slice.call(tb.rows);
    rows.sort(function (a, b) {
      var x = a.dataset[k], y = b.dataset[k];
      if (num) { x = x === '' ? -Infinity : +x; y = y === '' ? -Infinity : +y; }
      return (x < y ? -1 : x > y ? 1 : 0) * (up ? 1 : -1);
    });
    rows.forEach(function (r) { tb.appendChild(r); });
  });
});
"""

_CSS = """
body{font:14px sans-serif;margin:1em}table{border-collapse:collapse}
td,th{border-bottom:1px solid #ddd;padding:4px 8px;vertical-align:top;text-align:left}
th[data-k]{cursor:pointer;text-decoration:underline dotted}
img{width:360px;display:block}.weak{color:#b00;font-weight:bold}.failed,.skipped{color:#777}
.n{text-align:right;font-variant-numeric:tabular-nums}
"""


def write_html(out, records, title="osteon batch") -> Path:
    """The contact sheet: one row per model, weakest first; click a column head to sort."""
    recs = _order(_printable(records))
    n_ok = sum(r["status"] == "ok" for r in recs)
    n_weak = sum((r.get("stress_ratio") or 0) > 1 for r in recs)
    e = html.escape
    rows = []
    for r in recs:
        ratio = r.get("stress_ratio")
        cls = r["status"] if r["status"] != "ok" else ("weak" if (ratio or 0) > 1 else "")
        pic = (
            f'<a href="{e(MODELS_DIR)}/{e(r["png"])}"><img loading="lazy" '
            f'src="{e(MODELS_DIR)}/{e(r["png"])}" alt="{e(r["id"])}"></a>'
            if r.get("png") else ""
        )
        link = (
            f' (<a href="{e(r["json"])}">json</a>)' if r.get("json") else ""
        )
        mx = r.get("max_stress_mpa")
        rows.append(
            "<tr data-ratio=\"{ratio}\" data-stress=\"{mx}\" data-faces=\"{faces}\" "
            "data-model=\"{model}\" data-status=\"{status}\" data-seconds=\"{secs}\">"
            "<td>{pic}</td><td>{name}{link}<br><small>{path}</small></td>"
            "<td class=\"n {cls}\">{ratio_t}</td><td class=\"n\">{mx_t}</td>"
            "<td class=\"n\">{faces}</td><td class=\"n\">{bones}</td><td>{weak}</td>"
            "<td>{flags}</td><td class=\"{cls}\">{status_t}</td><td class=\"n\">{secs_t}</td>"
            "</tr>".format(
                ratio="" if ratio is None else f"{ratio:.6g}",
                mx="" if mx is None else f"{mx:.6g}",
                faces=r.get("faces", "") if r.get("faces") is not None else "",
                model=e(r["id"]),
                status=e(r["status"]),
                secs=f"{r.get('seconds', 0):.4g}",
                pic=pic,
                name=e(r["id"]),
                link=link,
                path=e(r["model"]),
                cls=cls,
                ratio_t="" if ratio is None else f"{ratio:.2f}",
                mx_t="" if mx is None else f"{mx:.1f}",
                bones=r.get("bone_count", "") if r.get("bone_count") is not None else "",
                weak=e(_weak_names(r)),
                flags=e(", ".join(r.get("flags") or [])),
                status_t=e(_status_text(r)),
                secs_t=f"{r.get('seconds', 0):.2f}",
            )
        )
    head = (
        "<tr><th>stress picture</th><th data-k=\"model\">model</th>"
        "<th data-k=\"ratio\" data-num=1 data-dir=\"desc\">σ/[σ]</th>"
        "<th data-k=\"stress\" data-num=1>max σ MPa</th><th data-k=\"faces\" data-num=1>faces</th>"
        "<th>bones</th><th>weak bones</th><th>flags</th><th data-k=\"status\">status</th>"
        "<th data-k=\"seconds\" data-num=1>s</th></tr>"
    )
    doc = (
        f"<!doctype html><html><head><meta charset=\"utf-8\"><title>{e(title)}</title>"
        f"<style>{_CSS}</style></head><body><h1>{e(title)}</h1>"
        f"<p>{len(recs)} models: {n_ok} analysed, {n_weak} weak (σ/[σ] &gt; 1), "
        f"{len(recs) - n_ok} skipped or failed. Weakest first; click a column head to sort."
        "</p><table><thead>" + head + "</thead><tbody>\n" + "\n".join(rows) +
        f"\n</tbody></table><script>{_JS}</script></body></html>\n"
    )
    path = Path(out) / "summary.html"
    write_atomic(path, doc)
    return path


def write_summaries(out) -> list[dict]:
    """Re-write ``summary.csv`` and ``summary.html`` from every line of ``results.jsonl``."""
    records = read_results(out)
    write_csv(out, records)
    write_html(out, records,
               title=f"osteon batch: {printable(os.path.basename(os.path.abspath(out)))}")
    return records
