"""The time line of the procedure: alignment first, then every navigation pass starts where it ended.

::

    log time  0 h ........ 4 h ............................ 16 h ........................... 76 h (88 h)
              |  alignment  |  navigation hours 0-12        |                                 |
              | coarse+fine |  -> features (lat at 12 h,    |                                 |
              |  (rotating) |     temperature over 12 h)    |                                 |
              |             |  navigation hours 0-72 -> true drift, evaluation  -------------->|

* Alignment uses the first ``align_h`` hours of the log (samples 0 .. round(align_h * 3600 * rate) - 1).
* Every navigation pass (features, true drift, evaluation) starts at the end of alignment, from the aligned
  attitude and velocity, with the estimated x/y gyro biases and all accelerometer biases compensated; the
  z-gyro compensation is the pass's trial drift (0 for the features).
* Hours of navigation are counted from that start: the features use navigation hours 0-12 (log hours 4-16),
  the true drift and the evaluation hours 0-72 (log hours 4-76). Longer logs are allowed (88 h); the samples
  after the last hour needed are not read.
"""

from __future__ import annotations

from dataclasses import dataclass

__all__ = ["Timeline", "DEFAULT_TIMELINE"]


@dataclass(frozen=True)
class Timeline:
    """Durations of the procedure [h].

    Attributes
    ----------
    align_h : float
        Alignment span at the start of the log (coarse + fine), default 4 h.
    features_h : float
        Free navigation after alignment that yields the features, default 12 h.
    truth_h : float
        Free navigation after alignment over which the true drift is found and the compensation evaluated,
        default 72 h.
    coarse_s : float
        Coarse alignment span at the start of the alignment [s] (default 300 s).
    """

    align_h: float = 4.0
    features_h: float = 12.0
    truth_h: float = 72.0
    coarse_s: float = 300.0

    def __post_init__(self):
        for name in ("align_h", "features_h", "truth_h"):
            v = getattr(self, name)
            if not v > 0:
                raise ValueError(f"Timeline: {name} must be > 0 h, got {v!r}")
        if not 0 < self.coarse_s < self.align_h * 3600.0:
            raise ValueError(f"Timeline: coarse_s must be in (0, align_h * 3600) s, got {self.coarse_s!r}")

    def log_hours_for(self, nav_hours: float) -> float:
        """Log length [h] needed to navigate `nav_hours` after the alignment."""
        return self.align_h + nav_hours


DEFAULT_TIMELINE = Timeline()
"""4 h alignment, 12 h features, 72 h truth and evaluation."""
