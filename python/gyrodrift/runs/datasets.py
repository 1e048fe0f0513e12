"""Embedded data sets, loaded in the scikit-learn ``datasets`` style.

``load_paper()`` returns the 32 runs of Yu et al. 2013 (Tables 1 and 2): 22 training runs and 10 test runs
recorded from 2009-11-08 to 2012-04-14 at latitude 28.222 deg.
"""

from __future__ import annotations

from importlib import resources

from sklearn.utils import Bunch

from gyrodrift.runs.table import PAPER_LAT0_DEG, RunTable, read_runs_csv

PAPER_DESCR = """\
Yu, Zhang, Xie, Long (2013), "Identification of axial RLG drifts in single-axis rotation inertial
navigation system based on CPSO-LSSVM", Systems Engineering and Electronics 35(5).
32 initial alignments of a single-axis rotation RLG INS on a static base at latitude 28.222 deg.
Inputs: latitude at the 12th hour of free navigation (lat_deg) and the temperature range over the
12 h (temp_min_c, temp_max_c). Target: the axial gyro drift (drift_deg_h) that minimised the 72 h
position error offline. Runs 1-22 train (Table 1), 23-32 test (Table 2, renumbered 1-10 in the paper).
"""


def paper_csv_path():
    """Path of the embedded CSV with the paper's Tables 1 and 2 (a context-free Traversable)."""
    return resources.files("gyrodrift").joinpath("data", "paper_runs.csv")


def load_paper() -> Bunch:
    """The paper's 32 runs, split as in the paper.

    Returns
    -------
    Bunch with
        ``runs`` (RunTable, all 32), ``train`` and ``test`` (RunTable, 22 and 10 runs),
        ``lat0_deg`` (28.222), ``feature_names`` (the raw input columns, before any encoding:
        ``lat_deg``, ``temp_min_c``, ``temp_max_c``), ``target_names`` (``drift_deg_h``), ``DESCR``.
    """
    with resources.as_file(paper_csv_path()) as path:
        runs: RunTable = read_runs_csv(path, lat0_deg=PAPER_LAT0_DEG, require_truth=True)
    return Bunch(
        runs=runs,
        train=runs.select(runs.split == "train"),
        test=runs.select(runs.split == "test"),
        lat0_deg=PAPER_LAT0_DEG,
        feature_names=("lat_deg", "temp_min_c", "temp_max_c"),
        target_names=("drift_deg_h",),
        DESCR=PAPER_DESCR,
    )
