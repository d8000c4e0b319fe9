"""The one list of result fields (cpp/include/osteon/result_fields.hpp) and the one options
object (osteon.AnalysisOptions): every engine output reaches Analysis with its documented shape,
dtype and docstring line; settings as keywords or as options= give bit-identical results."""

import dataclasses
import inspect
import pickle

import numpy as np
import osteon
import pytest
from osteon import _core
from shapes import capsule_along, merge

# An L of two round capsules (r = 3 mm) with a loose capsule beside it: sections, a joint, a
# free end, a loose piece.
ARM = capsule_along([0, 0, 0], [30, 0, 0], 3.0, n=32, stations=16)
FOREARM = capsule_along([30, 0, 0], [30, 0, 25], 3.0, n=32, stations=12)
LOOSE = capsule_along([10, 20, 0], [20, 20, 0], 2.0, n=24, stations=6)
SKELETON = osteon.Skeleton([[0, 0, 0], [30, 0, 0]], [[30, 0, 0], [30, 0, 25]], [-1, 0],
                           ["upper", "lower"])
SETTINGS = {"force": 12.0, "allowable_stress": 40.0, "interval": 1.5, "root": "upper",
            "gap_tolerance": 0.05, "threads": 1, "local_cuts": False,
            "build_direction": (0.0, 1.0, 1.0), "layer_strength_ratio": 0.5,
            "keep_outlines": True, "min_thickness": 0.4, "junctions": False}


@pytest.fixture(scope="module")
def model():
    return merge(ARM, FOREARM, LOOSE)


def same(a, b) -> bool:
    """Bit for bit: every result field and every recorded setting."""
    for name in [r[0] for r in osteon.RESULT_FIELDS] + ["allowable_stress", "force", "interval",
                                                         "build_direction", "min_thickness",
                                                         "layer_strength_ratio", "bone_names"]:
        x, y = getattr(a, name), getattr(b, name)
        if isinstance(x, list) and x and isinstance(x[0], np.ndarray):
            if len(x) != len(y) or not all(np.array_equal(p, q) for p, q in zip(x, y)):
                return False
        elif not np.array_equal(np.asarray(x), np.asarray(y), equal_nan=np.asarray(x).dtype.kind
                                == "f"):
            return False
    return True


def test_every_engine_field_reaches_analysis_with_its_shape(model):
    v, f = model
    a = osteon.analyze(v, f, SKELETON, **SETTINGS)
    n_sections, n_vertices = a.num_sections, len(v)
    assert n_sections == osteon.estimate_sections(SKELETON, SETTINGS["interval"]) > 20
    assert len(a.loose_pieces) == 1 and len(a.loose_pieces[0]) == len(LOOSE[0])
    fields = {f.name for f in dataclasses.fields(osteon.Analysis)}
    sizes = {"S": n_sections, "V": n_vertices, "3": 3,
             "P": len(a.outline_points), "L+1": len(a.outline_loop_start), "S+1": n_sections + 1}
    assert sizes["L+1"] == a.outline_section_start[-1] + 1
    assert sizes["P"] == a.outline_loop_start[-1] > 0
    for name, shape, dtype, unit, doc in osteon.RESULT_FIELDS:
        assert name in fields, name
        value = getattr(a, name)
        if shape == "()":
            assert type(value).__name__ == dtype, name
        elif shape == "[(n,)]":
            assert isinstance(value, list), name
            assert all(p.ndim == 1 and p.dtype == np.int32 for p in value), name
        else:
            want = tuple(sizes[d] for d in shape.strip("()").split(",") if d)
            # no junction here (junctions=False), no print profile (no infill loops)
            if name.startswith(("cut_outline", "infill_outline")):
                want = {"(P,3)": (0, 3), "(L+1,)": (1,), "(S+1,)": (n_sections + 1,)}[shape]
            assert value.shape == want, (name, value.shape, want)
            assert value.dtype == np.dtype(dtype), name
        # documented in Analysis's docstring with its shape and unit
        line = next(ln for ln in osteon.Analysis.__doc__.splitlines()
                    if ln.lstrip().startswith(f"- ``{name}``"))
        assert shape in line and unit in line, (name, line)
        assert doc.split()[0] in osteon.Analysis.__doc__


def test_the_binding_hands_over_exactly_the_table(model):
    v, f = model
    an = osteon.Analyzer(f, len(v), SKELETON)
    d = an._core.run(v, SKELETON._engine(), None)
    assert set(d) == {r[0] for r in osteon.RESULT_FIELDS} | {"thickness_pending"}
    assert list(osteon.RESULT_FIELDS) == [tuple(r) for r in _core.result_fields()]


def test_options_equal_keywords_bit_for_bit(model):
    v, f = model
    options = osteon.AnalysisOptions(**SETTINGS)
    by_keywords = osteon.analyze(v, f, SKELETON, **SETTINGS)
    by_options = osteon.analyze(v, f, SKELETON, options=options)
    assert same(by_keywords, by_options)
    analyzer = osteon.Analyzer(f, len(v), SKELETON, options=options)
    assert analyzer.options == options and same(analyzer.run(v), by_keywords)
    # a different setting does change the result (the comparison can fail)
    other = osteon.analyze(v, f, SKELETON, options=dataclasses.replace(options, force=13.0))
    assert not same(other, by_options)
    assert np.allclose(other.moment[by_options.valid] / by_options.moment[by_options.valid],
                       13.0 / 12.0)
    # pickling keeps every field (the deferred thickness filled in first)
    assert same(pickle.loads(pickle.dumps(by_options)), by_keywords)


def test_correct_takes_options_bit_for_bit(model):
    v, f = merge(ARM, FOREARM)
    kw = {"force": 30.0, "allowable_stress": 20.0, "interval": 2.0, "junctions": False}
    a = osteon.correct(v, f, SKELETON, None, max_rounds=2, **kw)
    b = osteon.correct(v, f, SKELETON, None, max_rounds=2, options=osteon.AnalysisOptions(**kw))
    assert a.num_rounds == b.num_rounds > 0
    assert np.array_equal(a.vertices, b.vertices)
    assert same(a.after, b.after) and same(a.before, b.before)


def test_options_are_checked_once_with_named_errors(model):
    v, f = model
    with pytest.raises(ValueError, match="interval must be a positive finite number"):
        osteon.AnalysisOptions(interval=0)
    with pytest.raises(ValueError, match="build_direction must be a finite non-zero 3-vector"):
        osteon.AnalysisOptions(build_direction=(0, 0, 0))
    with pytest.raises(ValueError, match="not both"):
        osteon.analyze(v, f, SKELETON, options=osteon.AnalysisOptions(), force=3.0)
    with pytest.raises(ValueError, match="options must be an osteon.AnalysisOptions"):
        osteon.analyze(v, f, SKELETON, options={"force": 3.0})
    with pytest.raises(TypeError):
        osteon.analyze(v, f, SKELETON, forse=3.0)
    o = osteon.AnalysisOptions(build_direction=(0, 0, 2), min_thickness=None, threads=np.int64(2))
    assert o.build_direction == (0.0, 0.0, 1.0) and o.min_thickness == 0.8 and o.threads == 2


def test_every_option_is_a_keyword_of_the_three_entry_points():
    names = [f.name for f in dataclasses.fields(osteon.AnalysisOptions)]
    for fn in (osteon.analyze, osteon.Analyzer, osteon.correct):
        params = inspect.signature(fn).parameters
        assert set(names) | {"options"} <= set(params), fn
        assert all(f"``{n}``" in inspect.getdoc(fn if fn is not osteon.Analyzer
                                                else fn.__init__) for n in names)


def test_engine_arguments_are_checked_options():
    from osteon.settings import Settings, engine_arguments

    kw = engine_arguments(Settings(force_n=20.0, interval_mm=1.0, build_direction=(0, 2, 0)),
                          ["upper", "lower"])
    o = osteon.AnalysisOptions(**kw)
    assert o.build_direction == (0.0, 1.0, 0.0) and o.interval == 1.0
    assert kw["build_direction"] == [0.0, 2.0, 0.0]  # the user's numbers, for the report
    with pytest.raises(ValueError, match="^section interval must be a positive"):
        engine_arguments(Settings(force_n=20.0, interval_mm=-1.0), [])
