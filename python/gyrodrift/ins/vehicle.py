"""The vehicle's attitude from the navigated IMU attitude and the turntable angle.

The IMU turns on its table about body Up relative to the vehicle: C_b^n = C_v^n Rz(alpha), with C_v^n the
vehicle's attitude (the IMU's at table angle 0: the vehicle's heading frame times the mounting) and alpha the
table angle (counter-clockwise positive). So C_v^n = C_b^n Rz(-alpha), and its Euler angles (pitch, roll, yaw with
C = Rz(yaw) Rx(pitch) Ry(roll), the core's convention) are the vehicle's. With a level IMU the vehicle yaw is the
IMU yaw minus the table angle.
"""

from __future__ import annotations

import os
from pathlib import Path
from typing import Any

import numpy as np

__all__ = ["vehicle_attitude_rad", "table_angles_deg"]


def vehicle_attitude_rad(
    pitch_rad: np.ndarray, roll_rad: np.ndarray, yaw_rad: np.ndarray, table_rad: np.ndarray
) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """(pitch, roll, yaw) [rad] of C_b^n Rz(-table) for IMU Euler angles and table angles [rad] (arrays)."""
    sp, cp = np.sin(pitch_rad), np.cos(pitch_rad)
    sr, cr = np.sin(roll_rad), np.cos(roll_rad)
    sy, cy = np.sin(yaw_rad), np.cos(yaw_rad)
    # C_b^n = Rz(yaw) Rx(pitch) Ry(roll): the entries the Euler angles of C Rz(-a) need.
    c00 = cy * cr - sy * sp * sr
    c01 = -sy * cp
    c10 = sy * cr + cy * sp * sr
    c11 = cy * cp
    c20 = -cp * sr
    c21 = sp
    c22 = cp * cr
    sa, ca = np.sin(table_rad), np.cos(table_rad)
    # (C Rz(-a))[i][0] = C[i][0] cos a - C[i][1] sin a, [i][1] = C[i][0] sin a + C[i][1] cos a, [i][2] = C[i][2].
    v01 = c00 * sa + c01 * ca
    v11 = c10 * sa + c11 * ca
    v20 = c20 * ca - c21 * sa
    v21 = c20 * sa + c21 * ca
    pitch = np.arcsin(np.clip(v21, -1.0, 1.0))
    roll = np.arctan2(-v20, c22)
    yaw = np.arctan2(-v01, v11)
    return pitch, roll, yaw


def table_angles_deg(source: Any, indices: np.ndarray) -> np.ndarray | None:
    """The ``table_angle_deg`` of an IMU source at the 0-based sample `indices` (increasing), or None when the
    source has no table angle: an in-memory run (``ImuData``) or a Parquet file with that column (read by row
    group, only the rows asked kept)."""
    columns = getattr(source, "columns", None)
    if isinstance(columns, dict) and "table_angle_deg" in columns:
        return np.asarray(columns["table_angle_deg"], dtype=float)[indices]
    path = source if isinstance(source, (str, os.PathLike)) else None
    if path is None or Path(path).suffix.lower() not in (".parquet", ".pq"):
        return None
    import pyarrow.parquet as pq

    pf = pq.ParquetFile(path)
    if "table_angle_deg" not in pf.schema_arrow.names:
        return None
    out = np.empty(len(indices))
    done, first = 0, 0
    for batch in pf.iter_batches(columns=["table_angle_deg"], batch_size=1 << 20):
        n = batch.num_rows
        end = int(np.searchsorted(indices, first + n))
        if end > done:
            out[done:end] = batch.column(0).to_numpy()[indices[done:end] - first]
            done = end
        first += n
        if done == len(indices):
            break
    return out if done == len(indices) else None
