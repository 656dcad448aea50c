"""The manifest of a batch: one row per item, appended as items complete.

``manifest.jsonl`` is the journal: one JSON object a line, each line written
in one ``write`` and flushed to disk after the item's folder is complete, so
an interrupted run leaves only complete rows (a torn last line, from a crash
mid-write, is ignored on reading and dropped at the next compaction). Rows
are flat: dotted keys (``metrics.weft_mean_pct``, ``shape.weight``), so the
table reads straight into pandas or Parquet.

At the end of a run :func:`compact` rewrites the journal sorted by item id,
the last row of each id kept, and, where ``pyarrow`` is installed, writes
``manifest.parquet`` beside it (columns = the union of the rows' keys).
"""

from __future__ import annotations

import json
import os
from pathlib import Path
from typing import Dict, Iterable, List, Optional

from ..fileio import dumps_json, write_text

JOURNAL = "manifest.jsonl"
PARQUET = "manifest.parquet"

#: Row keys that change from run to run with the same inputs (left out of determinism checks).
VOLATILE_PREFIXES = ("timings.", "worker")


def flatten(record: dict, prefix: str = "") -> dict:
    """``{"a": {"b": 1}}`` -> ``{"a.b": 1}`` (lists and scalars kept as values)."""
    out = {}
    for key, value in record.items():
        name = f"{prefix}{key}"
        if isinstance(value, dict):
            out.update(flatten(value, f"{name}."))
        else:
            out[name] = value
    return out


def read_rows(path) -> List[dict]:
    """The rows of a journal, in file order; unreadable lines (a torn last write) are skipped."""
    path = Path(path)
    if not path.exists():
        return []
    rows = []
    with open(path, encoding="utf-8") as f:
        for line in f:
            line = line.strip()
            if not line:
                continue
            try:
                row = json.loads(line)
            except json.JSONDecodeError:
                continue
            if isinstance(row, dict) and "id" in row:
                rows.append(row)
    return rows


def completed(rows: Iterable[dict]) -> Dict[str, dict]:
    """id -> row of the items whose latest row has status ``ok`` (a rerun skips them)."""
    latest: Dict[str, dict] = {}
    for row in rows:
        latest[row["id"]] = row
    return {k: r for k, r in latest.items() if r.get("status") == "ok"}


class Journal:
    """Appends rows to ``manifest.jsonl`` one complete line at a time."""

    def __init__(self, out_dir):
        self.path = Path(out_dir) / JOURNAL
        self.path.parent.mkdir(parents=True, exist_ok=True)
        self._torn_tail()
        self._file = open(self.path, "a", encoding="utf-8")

    def _torn_tail(self) -> None:
        # a crash mid-write leaves a last line without its newline: end it, so the next row
        # starts on a line of its own (the torn line is skipped on reading)
        if self.path.exists() and self.path.stat().st_size:
            with open(self.path, "rb+") as f:
                f.seek(-1, os.SEEK_END)
                if f.read(1) != b"\n":
                    f.write(b"\n")

    def extend(self, rows: Iterable[dict]) -> None:
        """Append ``rows`` in one write and one flush to disk (a task's items arrive together)."""
        text = "".join(dumps_json(row, indent=None) + "\n" for row in rows)
        if text:
            self._file.write(text)
            self._file.flush()
            os.fsync(self._file.fileno())

    def close(self) -> None:
        self._file.close()


def compact(out_dir) -> List[dict]:
    """Rewrite the journal sorted by item id (last row per id) and write Parquet where available.

    Returns the rows written.
    """
    path = Path(out_dir) / JOURNAL
    latest: Dict[str, dict] = {}
    for row in read_rows(path):
        latest[row["id"]] = row
    rows = [latest[k] for k in sorted(latest)]
    write_text(path, "".join(dumps_json(r, indent=None) + "\n" for r in rows))
    write_parquet(Path(out_dir) / PARQUET, rows)
    return rows


def write_parquet(path, rows: List[dict]) -> Optional[Path]:
    """``rows`` as a Parquet table (None, and nothing written, without ``pyarrow``)."""
    try:
        import pyarrow as pa
        import pyarrow.parquet as pq
    except ImportError:
        return None
    from ..fileio import write_bytes

    keys = sorted({k for r in rows for k in r})
    # lists and mixed types as JSON text: one type per column
    columns = {k: [(json.dumps(r[k]) if isinstance(r.get(k), (list, dict)) else r.get(k)) for r in rows] for k in keys}
    sink = pa.BufferOutputStream()
    pq.write_table(pa.table(columns), sink)
    return write_bytes(path, sink.getvalue().to_pybytes())


def comparable(rows: Iterable[dict]) -> List[dict]:
    """Rows without their volatile keys (timings, worker), sorted by id: equal for equal inputs."""
    return sorted(
        ({k: v for k, v in r.items() if not k.startswith(VOLATILE_PREFIXES)} for r in rows), key=lambda r: r["id"]
    )
