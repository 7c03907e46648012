"""The sweep format: many runs of worlds, seeds and mod parameters, for ``sandmod batch``.

A sweep is one TOML file::

    [sweep]
    worlds = ["piles.toml"]              # paths and globs, relative to this file
    seeds = { from = 0, to = 7 }         # or a list: [0, 1, 2]
    frames = 400                         # default: each world's own

    [parameters]                         # a grid: every combination is a run
    "elements.sand.friction" = [0.4, 0.6, 0.8]
    "world.gravity" = [1.0]

    [record]
    format = "gif"                       # or "none"; any output format
    snapshots = [400]                    # frames to save a snapshot at

    [metrics]
    frames = [200, 400]                  # frames to measure at (default: the last)

Every mistake, in the file or in what it names, is found by :func:`sandmod.jobs.batch.read_sweep`
before any run.
"""

from __future__ import annotations

import re
from typing import Annotated, Any

from pydantic import BaseModel, ConfigDict, Field, field_validator, model_validator

#: At most this many runs in one sweep.
MAX_RUNS = 100_000

#: What a parameter's dotted path may start with: a mod's element, or a world file's table.
PARAMETER = re.compile(r"^(elements\.[a-z][a-z0-9_]*(?::[a-z][a-z0-9_]*)?\.[a-z_]+(?:\.[a-z_]+)?|(world|render)\.[a-z_]+)$")


class _Strict(BaseModel):
    model_config = ConfigDict(extra="forbid")


class SeedRange(_Strict):
    """Seeds ``from`` to ``to``, both included."""

    from_: int = Field(alias="from", ge=0, le=2**32 - 1, description="The first seed.")
    to: int = Field(ge=0, le=2**32 - 1, description="The last seed.")

    @model_validator(mode="after")
    def _in_order(self) -> "SeedRange":
        if self.to < self.from_:
            raise ValueError("'to' must not be below 'from'")
        if self.to - self.from_ >= MAX_RUNS:
            raise ValueError(f"at most {MAX_RUNS} seeds")
        return self

    def values(self) -> list[int]:
        return list(range(self.from_, self.to + 1))


Seed = Annotated[int, Field(ge=0, le=2**32 - 1)]


class SweepInfo(_Strict):
    """The ``[sweep]`` table: which worlds, which seeds, how long."""

    worlds: list[str] = Field(min_length=1, max_length=1000, description="World files, or globs of them, relative to the sweep file.")
    seeds: Annotated[list[Seed], Field(max_length=MAX_RUNS)] | SeedRange = Field(
        default_factory=lambda: [0], description="Seeds to run each world with: a list (each seed once), or { from = 0, to = 99 }."
    )
    frames: int | None = Field(None, ge=1, le=100000, description="Frames each run simulates (default: each world's own).", examples=[300])

    @field_validator("seeds", mode="before")
    @classmethod
    def _unique_seeds(cls, seeds: Any) -> Any:
        if isinstance(seeds, list):
            if not seeds:
                raise ValueError("at least one seed")
            _unique(seeds)
        return seeds

    def seed_list(self) -> list[int]:
        return self.seeds.values() if isinstance(self.seeds, SeedRange) else list(self.seeds)


class RecordSettings(_Strict):
    """The ``[record]`` table: what each run keeps besides its metrics."""

    format: str = Field("none", min_length=1, description="An output format (gif, webp, apng, png-frames, a plugin's) or 'none'.", examples=["webp"])
    every: int | None = Field(None, ge=1, le=1000, description="Frames per image (default: the world's own).", examples=[4])
    scale: int | None = Field(None, ge=1, le=16, description="Pixels per cell (default: the world's own).", examples=[2])
    snapshots: list[Annotated[int, Field(ge=1, le=100000)]] = Field(
        default_factory=list, max_length=100, description="Frames to save the whole state at, as snapshots.",
        examples=[[250]],
    )


class MetricSettings(_Strict):
    """The ``[metrics]`` table: what is measured in each run, and when."""

    frames: list[Annotated[int, Field(ge=0, le=100000)]] = Field(
        default_factory=list, max_length=100, description="Frames to measure at (default: the last).",
        examples=[[100, 500]],
    )
    names: list[str] | None = Field(
        None, max_length=100, description="Metrics to take (default: all: counts, centre, extent, awake, heat, and plugins')."
    )


class SweepFile(_Strict):
    """A whole sweep file."""

    sweep: SweepInfo = Field(description="Worlds, seeds and frames.")
    parameters: dict[str, list[Any]] = Field(
        default_factory=dict,
        description="A grid of values by dotted path: 'elements.NAME.FIELD' into the mods, 'world.FIELD' or 'render.FIELD' "
        "into each world; every combination is a run. A path's values are all numbers, all text or all true/false, each "
        "listed once, and each must take effect. At most 100,000 runs in one sweep (worlds x combinations x seeds).",
        examples=[{"elements.sand.friction": [0.4, 0.8], "world.gravity": [0.5, 1.0]}],
    )
    record: RecordSettings = Field(default_factory=RecordSettings, description="What each run records.")
    metrics: MetricSettings = Field(default_factory=MetricSettings, description="What each run measures.")

    @field_validator("parameters")
    @classmethod
    def _paths(cls, parameters: dict[str, list[Any]]) -> dict[str, list[Any]]:
        for path, values in parameters.items():
            if not PARAMETER.match(path):
                raise ValueError(f"{path!r} is not 'elements.NAME.FIELD', 'world.FIELD' or 'render.FIELD'")
            if not values:
                raise ValueError(f"{path!r} needs at least one value")
            kinds = {_kind(value) for value in values}
            if None in kinds or len(kinds) > 1:
                raise ValueError(f"{path!r}: the values must be all numbers, all text or all true/false")
            try:
                _unique(values)
            except ValueError as error:
                raise ValueError(f"{path!r}: {error}") from None
        return parameters


def _kind(value: Any) -> str | None:
    """'number', 'text' or 'bool'; None for what a parameter cannot be (a list, a table, a date)."""
    if isinstance(value, bool):
        return "bool"
    if isinstance(value, (int, float)):
        return "number"
    return "text" if isinstance(value, str) else None


def _unique(values: list[Any]) -> None:
    seen = set()
    for value in values:
        if not isinstance(value, (int, float, str)):
            continue  # not a value at all: its own check says so
        if value in seen:
            raise ValueError(f"{value!r} is listed twice (each would be the same runs)")
        seen.add(value)
