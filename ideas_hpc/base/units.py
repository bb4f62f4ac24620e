"""Unit constants: the SI value of one unit (SPEC: SI inside, user units at the boundary).

Convert at the boundary by multiplying (``z_km * KM`` is metres, ``angle_deg *
DEG`` is radians) and back for display by dividing (``r_m / KM`` is km). Only
the boundary layer uses them; ``core/`` kernels take SI values.
"""

from __future__ import annotations

import math

#: Kilometre, m.
KM = 1e3
#: Centimetre, m.
CM = 1e-2
#: Millimetre, m.
MM = 1e-3
#: Micrometre, m.
UM = 1e-6
#: Degree, rad.
DEG = math.pi / 180.0
#: Minute, s.
MINUTE = 60.0
#: Hour, s.
HOUR = 3600.0
#: Revolution per minute, rad/s.
RPM = 2.0 * math.pi / 60.0
