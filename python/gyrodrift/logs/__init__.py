"""IMU logs: one reader per format, log formats, the plausibility validator and the chunked view the core streams."""

from gyrodrift.logs.imu_log import (
    DEFAULT_CHUNK_SAMPLES,
    INCREMENT_COLUMNS,
    ImplausibleLogError,
    ImuLog,
    LogChunk,
    LogError,
    LogTruth,
    RATE_COLUMNS,
    REF_HEIGHT_COLUMN,
    STATIC_CHECK_SPAN_S,
    TRUTH_COLUMNS,
    open_log,
)

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
    "TRUTH_COLUMNS",
    "open_log",
]
