"""Physical constants (SI)."""

#: Newtonian constant of gravitation, m^3 kg^-1 s^-2 (CODATA 2018), as SPEC section 1.
G = 6.67430e-11
#: Astronomical unit, m (IAU 2012 Resolution B2).
AU = 1.495978707e11
#: Solar radiation pressure at 1 AU on an absorbing surface, N/m^2 (SPEC section 4).
P_SUN_1AU = 4.56e-6
#: Sun's gravitational parameter, m^3/s^2 (IAU 2015 nominal).
MU_SUN = 1.32712440018e20
