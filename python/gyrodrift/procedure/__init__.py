"""gyrodrift.procedure: from an IMU log to a compensated navigation (the paper's procedure).

Time line (`Timeline`): alignment over log hours 0-4; every navigation pass starts at the end of alignment;
the features use navigation hours 0-12, the true drift and the evaluation hours 0-72 (logs >= 76 h).

Public API (plain functions returning dataclasses; the CLI in `gyrodrift.cli.procedure` wraps them)
--------------------------------------------------------------------------------------------------------
::

    align_log(log, ...) -> Alignment; write_alignment(alignment, out_dir)
    navigate_after_alignment(log, alignment, drifts_deg_h, hours, ...) -> PassResult
    navigate(imu, *, hours=None, drift_law=None, initial="auto", ..., out_dir=None, plot=False) -> NavResult
        (the ``navigate`` command: from the log's truth or its alignment; nav.parquet, summary.json)
    extract_features(log, ..., with_truth=False) -> RunFeatures
    write_features_csv(rows, path, curves=None)
    find_true_drift(log, criterion="final", hours=72, ...) -> TrueDrift; write_truth(truth, out_dir)
    evaluate_compensation(log, drift_deg_h, hours=72, ...) -> Evaluation; write_evaluation(ev, out_dir)
    identify(log, model, ...) -> Identification; write_identification(res, out_dir)
    smooth_log(log, noise=None, ...) -> SmootherEstimate (the 16 h smoother: drift, 1-sigma, history)

Layers: the result dataclasses live in `gyrodrift.procedure.results`; the algorithms import them (never
matplotlib or the file writer); `gyrodrift.procedure.figures` draws results and `gyrodrift.procedure.writers`
writes them, each set of files published together (docs/outputs.md).

Logs are opened with `gyrodrift.logs.open_log` (Parquet or CSV, validated while streaming). See docs/procedure.md.
"""

from gyrodrift.procedure.align import align_log
from gyrodrift.procedure.evaluate import evaluate_compensation
from gyrodrift.procedure.features import extract_features, features_run_table
from gyrodrift.procedure.identify import identify
from gyrodrift.procedure.navigate import navigate
from gyrodrift.procedure.noise import SensorNoise, estimate_white_noise
from gyrodrift.procedure.passes import navigate_after_alignment
from gyrodrift.procedure.results import (
    Alignment,
    Evaluation,
    Identification,
    NavCurve,
    PassResult,
    RunFeatures,
    SmootherEstimate,
    TemperatureStats,
    TrueDrift,
)
from gyrodrift.procedure.smoother import smooth_log
from gyrodrift.procedure.timeline import DEFAULT_TIMELINE, Timeline
from gyrodrift.procedure.truth import CRITERIA, find_true_drift
from gyrodrift.procedure.writers import (
    write_alignment,
    write_evaluation,
    write_features_csv,
    write_identification,
    write_truth,
)

__all__ = [
    "Alignment",
    "CRITERIA",
    "DEFAULT_TIMELINE",
    "Evaluation",
    "Identification",
    "NavCurve",
    "PassResult",
    "RunFeatures",
    "SensorNoise",
    "SmootherEstimate",
    "TemperatureStats",
    "Timeline",
    "TrueDrift",
    "align_log",
    "estimate_white_noise",
    "evaluate_compensation",
    "extract_features",
    "features_run_table",
    "find_true_drift",
    "identify",
    "navigate",
    "navigate_after_alignment",
    "smooth_log",
    "write_evaluation",
    "write_alignment",
    "write_features_csv",
    "write_identification",
    "write_truth",
]
