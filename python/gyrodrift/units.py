"""Unit conversions between the SI used inside gyrodrift and the units engineers read.

Drift in deg/h, random walk in deg/sqrt(h), accelerometer bias in ug (1 ug = 9.80665e-6 m/s^2),
angles in arcsec, distances in nautical miles (1 nmi = 1852 m).
"""

import math

from gyrodrift.earth import NMI_M

DEG = math.pi / 180.0
"""One degree [rad]."""
ARCSEC = DEG / 3600.0
"""One arcsecond [rad]."""
HOUR = 3600.0
"""One hour [s]."""
DEG_PER_H = DEG / HOUR
"""One deg/h [rad/s]."""
DEG_PER_SQRT_H = DEG / math.sqrt(HOUR)
"""One deg/sqrt(h) [rad/sqrt(s)]."""
MICRO_G = 9.80665e-6
"""One ug [m/s^2] (standard gravity 9.80665 m/s^2)."""
NMI = NMI_M
"""One international nautical mile [m]."""
