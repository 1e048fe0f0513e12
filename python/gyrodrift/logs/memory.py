"""The in-memory reader of IMU logs: a mapping of the reader's column names to 1-D numpy arrays (`array_source`)."""

from __future__ import annotations

from collections.abc import Iterator, Mapping
from dataclasses import dataclass, field
from typing import Any

import numpy as np

from gyrodrift.logs.columns import REF_HEIGHT_COLUMN, TEMPERATURE, TIME, TRUTH_COLUMNS
from gyrodrift.logs.source import (
    RATE_PROBE,
    Layout,
    LogError,
    LogSource,
    LogTruth,
    Provenance,
    RawBlock,
    SampleRate,
    check_rate,
    rate_from_times,
)
from gyrodrift.site import Site

__all__ = ["ArraySource", "array_source"]


@dataclass(frozen=True, kw_only=True)
class ArraySource(LogSource):
    """Columns held in memory (not copied), cut into blocks as a file's rows are."""

    format: str = "memory"

    arrays: dict[str, np.ndarray] = field(default_factory=dict, repr=False, compare=False)

    def blocks(self, chunk_samples: int) -> Iterator[RawBlock]:
        wanted = self.layout.wanted()
        for a in range(0, self.n_samples, chunk_samples):
            b = min(self.n_samples, a + chunk_samples)
            yield self.layout.raw_block({c: self.arrays[c][a:b] for c in wanted})


def array_source(
    columns: Mapping[str, Any],
    *,
    rate_hz: float | None,
    source_site: Site | None,
    truth: LogTruth | None,
    label: str,
    require_temperature: bool,
    static_s: float | None,
) -> ArraySource:
    """The source of in-memory `columns` (see `gyrodrift.logs.log.ImuLog.from_arrays`): 1-D arrays of numbers of one
    length; the rate from the time stamps unless given."""
    layout = Layout.from_header(list(columns), label, require_temperature=require_temperature, file=False)
    arrays: dict[str, np.ndarray] = {}
    n = None
    for c in [TIME.name, *layout.columns, TEMPERATURE.name, *TRUTH_COLUMNS, REF_HEIGHT_COLUMN]:
        if c not in columns:
            continue
        a = np.asarray(columns[c])
        if a.ndim != 1 or a.dtype.kind not in "iuf":
            raise LogError(f"{label}, column {c}: expected a 1-D array of numbers, got {a.dtype} {a.shape}")
        if n is not None and len(a) != n:
            raise LogError(f"{label}, column {c}: {len(a)} values, expected {n} like t_s")
        n = len(a)
        arrays[c] = a
    if n is None or n < 2:
        raise LogError(f"{label}: {n or 0} sample(s); a log needs many")
    if rate_hz is None:
        rate = rate_from_times(np.asarray(arrays[TIME.name][: RATE_PROBE + 1], float), label)
    else:
        rate = SampleRate(check_rate(rate_hz, label), "given")
    known = Provenance(source_site, truth, static_s)
    return ArraySource(label=label, layout=layout, rate=rate, n_samples=n, provenance=known, arrays=arrays)
