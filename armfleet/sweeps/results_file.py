"""A sweep's results file: Parquet, appended a row group at a time as runs finish.

Rows are written as they come (a row group per flush), and the file is closed properly
on Ctrl-C, so an interrupted sweep keeps every finished run. Beside the file, while the
sweep runs, a journal (``<file>.journal``, Arrow's IPC stream format) receives the same
rows: a stream is readable up to its last complete batch, so even a driver killed
outright (no Parquet footer written) loses nothing that finished; :func:`read_results`
falls back to it, and the journal is removed once the Parquet file is closed.

The metric columns' types come from the first successful run (a bool stays a bool, an
int an int64, a float a float64, text a string); a later run whose metrics do not fit
becomes a failed row that says why.
"""

from __future__ import annotations

import os
from collections.abc import Sequence
from pathlib import Path
from typing import Any

import pyarrow as pa
import pyarrow.ipc as ipc
import pyarrow.parquet as pq

from armfleet.checks.user_paths import file_problem
from armfleet.sweeps.errors import SweepError
from armfleet.sweeps.results_schema import METADATA_KEY, RUN_COLUMNS, SweepMetadata
from armfleet.sweeps.run import Row

METRIC_TYPES: dict[type, pa.DataType] = {
    bool: pa.bool_(),
    int: pa.int64(),
    float: pa.float64(),
    str: pa.string(),
}


def journal_path(path: Path) -> Path:
    return path.with_name(path.name + ".journal")


def read_results(path: Path) -> pa.Table:
    """The rows of a results file; those of its journal instead when there is one (a
    sweep that did not close its file: the journal holds every row the file had, and more).

    Raises:
        SweepError: ``path`` is no regular file, is not a Parquet file (or is cut short),
            or holds no armfleet sweep metadata.
    """
    journal = journal_path(path)
    if file_problem(journal) is None:
        table = _read_journal(journal)
    else:
        problem = file_problem(path)
        if problem is not None:
            raise SweepError(f"sweep results {path}: {problem}")
        try:
            table = pq.read_table(path)
        except (pa.ArrowException, OSError) as exc:
            text = str(exc).strip()
            reason = text.splitlines()[0] if text else type(exc).__name__
            raise SweepError(
                f"{path} is not a Parquet file, or it is cut short ({reason})"
            ) from None
    try:
        metadata = SweepMetadata.from_schema(table.schema)
    except (ValueError, TypeError):
        metadata = None
    if metadata is None:
        raise SweepError(
            f"{path} is not an armfleet sweep's results (its schema holds no "
            "armfleet.sweep metadata)"
        )
    return table


def _read_journal(journal: Path) -> pa.Table:
    batches = []
    schema = None
    try:
        with pa.OSFile(str(journal)) as source:
            reader = ipc.open_stream(source)
            schema = reader.schema
            while True:
                try:
                    batches.append(reader.read_next_batch())
                except StopIteration:
                    break
                except (pa.ArrowException, OSError):
                    break  # the batch being written when the driver died
    except (pa.ArrowException, OSError) as exc:
        raise SweepError(f"{journal} is not readable ({exc})") from None
    return pa.Table.from_batches(batches, schema=schema)


class ResultsWriter:
    """Writes rows of a sweep to ``path``, keeping ``kept`` rows (a resumed sweep's).

    Rows are written to ``<path>.partial`` and its journal; :meth:`close` finishes the
    Parquet file and moves it to ``path``, replacing the old one only then.
    """

    def __init__(
        self,
        path: Path,
        metadata: SweepMetadata,
        integer_parameters: frozenset[str] = frozenset(),
        kept: pa.Table | None = None,
    ) -> None:
        self.path = path
        self._integer_parameters = integer_parameters
        self._metadata = metadata
        self._partial = path.with_name(path.name + ".partial")
        self._journal = journal_path(path)
        self._pending: list[Row] = []
        self._schema: pa.Schema | None = None
        self._parquet: pq.ParquetWriter | None = None
        self._stream: ipc.RecordBatchStreamWriter | None = None
        self._sink: pa.OSFile | None = None
        self.written_seeds: set[int] = set()
        if kept is not None:  # a resumed sweep: its rows first, under the new metadata
            self.written_seeds.update(int(s) for s in kept.column("seed").to_pylist())
            self._schema = kept.schema.with_metadata({METADATA_KEY: metadata.to_json()})
            self._open()
            self._write(kept.cast(self._schema))

    @property
    def schema(self) -> pa.Schema | None:
        return self._schema

    def append(self, rows: Sequence[Row]) -> None:
        """Write ``rows`` (each seed once: a row of a seed already written is dropped)."""
        fresh = [row for row in rows if row["seed"] not in self.written_seeds]
        self.written_seeds.update(row["seed"] for row in fresh)
        self._pending.extend(fresh)
        if self._schema is None:
            first_ok = next((row for row in self._pending if row["ok"]), None)
            if first_ok is None:
                return  # the metric types are not known yet
            self._schema = self._schema_of(first_ok["metrics"])
            self._open()
        table = self._table(self._pending)
        self._pending = []
        self._write(table)

    def close(self) -> Path:
        """Finish the file (rows not yet written included) and put it at ``path``."""
        if self._pending or self._schema is None:
            if self._schema is None:
                self._schema = self._schema_of({})
                self._open()
            self._write(self._table(self._pending))
            self._pending = []
        assert self._parquet is not None and self._stream is not None and self._sink is not None
        self._parquet.close()
        self._stream.close()
        self._sink.close()
        os.replace(self._partial, self.path)
        self._journal.unlink(missing_ok=True)
        return self.path

    # -- internals -----------------------------------------------------------------
    def _schema_of(self, metrics: dict[str, Any]) -> pa.Schema:
        fields = [pa.field(name, kind) for name, (kind, _) in RUN_COLUMNS.items()]
        fields += [pa.field(name, self._parameter_type(name)) for name in self._parameters()]
        fields += [pa.field(name, METRIC_TYPES[type(value)]) for name, value in metrics.items()]
        metadata = SweepMetadata(
            **{
                **self._metadata.__dict__,
                "parameters": self._parameters(),
                "metrics": tuple(metrics),
            }
        )
        self._metadata = metadata
        return pa.schema(fields, metadata={METADATA_KEY: metadata.to_json()})

    def _parameters(self) -> tuple[str, ...]:
        return self._metadata.parameters

    def _parameter_type(self, name: str) -> pa.DataType:
        return pa.int64() if name in self._integer_parameters else pa.float64()

    def _open(self) -> None:
        assert self._schema is not None
        self._parquet = pq.ParquetWriter(self._partial, self._schema)
        self._sink = pa.OSFile(str(self._journal), "wb")
        self._stream = ipc.new_stream(self._sink, self._schema)

    def _write(self, table: pa.Table) -> None:
        assert self._parquet is not None and self._stream is not None and self._sink is not None
        if table.num_rows == 0:
            return
        self._parquet.write_table(table)
        self._stream.write_table(table)
        self._sink.flush()

    def _table(self, rows: list[Row]) -> pa.Table:
        assert self._schema is not None
        metrics = [name for name in self._schema.names if name in self._metadata.metrics]
        columns: dict[str, list[Any]] = {name: [] for name in self._schema.names}
        for row in rows:
            fitted = _fitted(row, metrics, self._schema)
            for name in self._schema.names:
                columns[name].append(fitted.get(name))
        return pa.table(
            {
                name: pa.array(values, self._schema.field(name).type)
                for name, values in columns.items()
            },
            schema=self._schema,
        )


def _fitted(row: Row, metrics: list[str], schema: pa.Schema) -> Row:
    """``row`` flattened (its metrics as columns), or failed if its metrics do not fit."""
    flat = {key: value for key, value in row.items() if key != "metrics"}
    given = row.get("metrics") or {}
    extra = [name for name in given if name not in metrics]
    problem = None
    if extra:
        problem = f"metric {extra[0]!r} is not among the first run's: {', '.join(metrics)}"
    for name in metrics:
        if problem or name not in given:
            continue
        value, kind = given[name], schema.field(name).type
        if kind == pa.float64() and isinstance(value, int) and not isinstance(value, bool):
            value = float(value)
        expected = next(t for t, arrow in METRIC_TYPES.items() if arrow == kind)
        if type(value) is not expected:
            problem = (
                f"metric {name!r} is a {type(value).__name__} here, a {expected.__name__} in "
                "the first run"
            )
        flat[name] = value
    if problem and flat.get("ok"):
        flat = {key: value for key, value in flat.items() if key not in metrics}
        flat.update(ok=False, error=f"TypeError: {problem}")
    return flat
