"""The columns of a sweep's results (one row per run) and the metadata stored with them.

A results file is Parquet. Its columns, in order:

- the run's own columns (:data:`RUN_COLUMNS`): ``seed``, ``ok``, ``error``, the wall
  times of its phases, the simulated time, the worker's host and process;
- the drawn parameters, one column per number (a vector's elements are ``name[i]``);
- the metrics the task returned, one column each (null in a failed run).

The schema's metadata, under :data:`METADATA_KEY`, is a JSON object
(:class:`SweepMetadata`) saying which columns are parameters and which are metrics.
"""

from __future__ import annotations

import json
from dataclasses import asdict, dataclass

import pyarrow as pa

#: Key of the sweep's metadata in the Parquet schema's key-value metadata.
METADATA_KEY = b"armfleet.sweep"

#: Columns every row has, with their types and meaning.
RUN_COLUMNS: dict[str, tuple[pa.DataType, str]] = {
    "seed": (pa.int64(), "the run's seed (base_seed + run index)"),
    "ok": (pa.bool_(), "the task returned its metrics"),
    "error": (pa.string(), "why the run failed (type: message), null if ok"),
    "wall_s": (pa.float64(), "wall time of the whole run in its worker [s]"),
    "bringup_s": (pa.float64(), "wall time of launching the spec (world, arms, objects) [s]"),
    "task_s": (pa.float64(), "wall time of the task, stepping included [s]"),
    "stepping_s": (pa.float64(), "wall time spent in World.step during the task [s]"),
    "sim_time_s": (pa.float64(), "simulated time when the task ended [s]"),
    "host": (pa.string(), "host name of the worker that ran it"),
    "pid": (pa.int64(), "process id of the worker that ran it"),
}


@dataclass(frozen=True)
class SweepMetadata:
    """What a results file is a sweep of.

    Attributes:
        scenario: the scenario as given (a shipped name or a file).
        spec: the launch spec's source.
        task: the task, as ``module:function`` or ``file.py:function``.
        base_seed: run i has seed ``base_seed + i``.
        runs: runs asked for (the file may hold fewer if the sweep was interrupted).
        parameters: the drawn parameters' columns, in order.
        metrics: the metrics' columns, in order.
        armfleet: armfleet's version that wrote the file.
        digest: the sweep's fingerprint (:attr:`SweepDefinition.digest`).
    """

    scenario: str
    spec: str
    task: str
    base_seed: int
    runs: int
    parameters: tuple[str, ...] = ()
    metrics: tuple[str, ...] = ()
    armfleet: str = ""
    digest: str = ""

    def to_json(self) -> bytes:
        return json.dumps(asdict(self)).encode()

    @classmethod
    def from_schema(cls, schema: pa.Schema) -> SweepMetadata | None:
        """The metadata in ``schema``, or None if it holds none (not a sweep's file)."""
        raw = (schema.metadata or {}).get(METADATA_KEY)
        if raw is None:
            return None
        data = json.loads(raw)
        data["parameters"] = tuple(data.get("parameters", ()))
        data["metrics"] = tuple(data.get("metrics", ()))
        known = set(cls.__dataclass_fields__)
        return cls(**{key: value for key, value in data.items() if key in known})
