"""CSV text of named columns: the one writer of the package's CSV (the measured-data files, the
command line's tables, the exports' neutral table)."""

from __future__ import annotations

import csv
import io
from pathlib import Path

import numpy as np

# numbers in the measured-data files this package writes (examples, demos, synthetic data)
FILE_NUMBER_FORMAT = "{:.10g}"


def csv_text(columns: dict[str, np.ndarray], number_format: str = "{:.12g}") -> str:
    """CSV text with a header row of the column names and one row per index (SI numbers)."""
    buf = io.StringIO()
    writer = csv.writer(buf, lineterminator="\n")
    writer.writerow(columns)
    for row in zip(*columns.values()):
        writer.writerow([v if isinstance(v, str) else number_format.format(v) for v in row])
    return buf.getvalue()


def written(text: str, path: str | Path | None) -> str:
    """``text``, written to ``path`` (UTF-8) first unless it is None."""
    if path is not None:
        Path(path).write_text(text, encoding="utf-8")
    return text
