"""The settings of a batch run: the shared :class:`osteon.settings.Settings` (the same as
``osteon analyze`` / ``correct`` and the add-on) plus what only a batch decides. mm, N, MPa."""

from __future__ import annotations

from dataclasses import asdict, dataclass, field, fields, replace

from ..settings import MAX_SECTIONS, Settings, engine_arguments

#: the CLI's defaults for the two settings the shared Settings leaves to the front end
DEFAULT_FORCE_N = 20.0
DEFAULT_INTERVAL_MM = 2.0
#: seconds one model of a batch may take (a hanging or huge model fails with this reason)
DEFAULT_MODEL_TIMEOUT_S = 300.0
_SIZE_MODES = {"LARGEST": None, "HEIGHT": "z", "X": "x", "Y": "y", "Z": "z"}


def _default_settings() -> Settings:
    import osteon

    return Settings(force_n=DEFAULT_FORCE_N, interval_mm=DEFAULT_INTERVAL_MM,
                    scaling=osteon.DEFAULT_SCALING)


@dataclass(frozen=True)
class BatchSettings:
    """What every model of a batch is analysed with.

    ``settings``: the shared :class:`osteon.settings.Settings` (force N, interval mm, material,
    strength MPa, safety factor, held bone, print size mm and how it is measured, correction
    limits). Batch only: ``correct`` (also run the correction and write the corrected mesh);
    ``png`` (render the contact-sheet picture, ``png_dpi``); ``allow_open`` (analyse open
    meshes too, flagged, instead of failing them); ``engine_threads`` (threads of the engine
    inside one task: 1, since the batch runs models in parallel; 0 = all cores);
    ``slicer_project`` ("prusaslicer", "bambu", "orca" or None): also reinforce each model under
    the settings' FDM print profile (:func:`osteon.reinforce`) and write ``ID.3mf`` for that
    slicer, the report's ``reinforcement`` listing the regions.
    ``model_timeout_s`` (seconds one model may take; over it the model fails with that reason
    and its worker process is killed with its process group, on every runner: the pool, one
    worker process for ``workers=1``, a child of the Dask worker on Dask; 0 = no limit); ``max_sections`` (a model whose section
    estimate is above it fails before the analysis, the estimate and memory in its reason:
    :func:`osteon.settings.section_budget`).
    """

    settings: Settings = field(default_factory=_default_settings)
    correct: bool = False
    png: bool = True
    png_dpi: int = 60
    allow_open: bool = False
    engine_threads: int = 1
    slicer_project: str | None = None
    model_timeout_s: float = DEFAULT_MODEL_TIMEOUT_S
    max_sections: int = MAX_SECTIONS

    @classmethod
    def from_any(cls, settings) -> BatchSettings:
        """From None, a BatchSettings, a :class:`osteon.settings.Settings`, or a dict whose
        keys are fields of either (``{"force_n": 20, "material": "PETG", "png": False}``)."""
        if settings is None:
            return cls()
        if isinstance(settings, cls):
            return settings
        if isinstance(settings, Settings):
            return cls(settings=settings)
        if isinstance(settings, dict):
            mine = {f.name for f in fields(cls)} - {"settings"}
            shared = {f.name for f in fields(Settings)}
            unknown = sorted(set(settings) - mine - shared)
            if unknown:
                raise ValueError(
                    f"unknown batch setting(s) {', '.join(unknown)}; known: "
                    f"{', '.join(sorted(mine | shared))}"
                )
            base = replace(_default_settings(), **{k: v for k, v in settings.items()
                                                   if k in shared})
            return cls(settings=base, **{k: v for k, v in settings.items() if k in mine})
        raise ValueError(
            f"settings must be a BatchSettings, Settings or dict, got {type(settings).__name__}"
        )

    def replace(self, **kw) -> BatchSettings:
        return replace(self, **kw)

    def as_dict(self) -> dict:
        d = asdict(self)
        d["settings"] = self.settings.as_dict()
        return d

    @property
    def allowable_mpa(self) -> float:
        return self.settings.allowable_stress_mpa()

    def height_and_axis(self) -> tuple[float | None, str | None]:
        """``load_model``'s (height_mm, axis) from the shared size mode."""
        mode = str(self.settings.size_mode).upper()
        if mode == "UNITS":
            return None, None
        if mode not in _SIZE_MODES:
            raise ValueError(f"size mode must be one of {', '.join(_SIZE_MODES)} or UNITS, "
                             f"got {self.settings.size_mode!r}")
        return float(self.settings.print_size_mm), _SIZE_MODES[mode]

    def engine_kwargs(self, bone_names) -> dict:
        """The engine's keyword arguments for one model (``osteon.settings.engine_arguments``)."""
        kw = engine_arguments(self.settings, bone_names, correct=self.correct)
        kw["threads"] = int(self.engine_threads)
        kw["max_sections"] = int(self.max_sections)  # the engine's own check, same limit
        return kw

    def check(self) -> None:
        """Raise ValueError naming the first bad setting (before any model is read)."""
        engine_arguments(replace(self.settings, held_bone=None), [], correct=self.correct)
        h, _ = self.height_and_axis()
        if h is not None and not h > 0:
            raise ValueError(f"print size must be a positive number of mm, got {h}")
        if self.slicer_project is not None:
            from ..slicer3mf import SLICERS

            if self.slicer_project not in SLICERS:
                raise ValueError(f"slicer_project must be one of {', '.join(SLICERS)}, "
                                 f"got {self.slicer_project!r}")
        if not (float(self.model_timeout_s) >= 0):
            raise ValueError(f"model timeout must be >= 0 s (0 = none), got "
                             f"{self.model_timeout_s}")
        if int(self.max_sections) < 1:
            raise ValueError(f"max sections must be >= 1, got {self.max_sections}")
        if self.engine_threads < 0:
            raise ValueError(f"engine_threads must be >= 0, got {self.engine_threads}")
