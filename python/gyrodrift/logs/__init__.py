"""IMU logs: one reader per format, log formats, the plausibility validator and the chunked view the core streams."""

from gyrodrift.logs.columns import INCREMENT_COLUMNS, RATE_COLUMNS, REF_HEIGHT_COLUMN
from gyrodrift.logs.log import ImuLog, LogChunk, open_log
from gyrodrift.logs.plausibility import STATIC_CHECK_SPAN_S, ImplausibleLogError
from gyrodrift.logs.source import DEFAULT_CHUNK_SAMPLES, LogError, LogTruth

__all__ = [
    "DEFAULT_CHUNK_SAMPLES",
    "INCREMENT_COLUMNS",
    "ImplausibleLogError",
    "ImuLog",
    "LogChunk",
    "LogError",
    "LogTruth",
    "RATE_COLUMNS",
    "REF_HEIGHT_COLUMN",
    "STATIC_CHECK_SPAN_S",
    "open_log",
]
