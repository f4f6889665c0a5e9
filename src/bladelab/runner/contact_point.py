"""The lowest point of a runner's contact sphere or ellipse (numba), shared by the explicit
force loop (:func:`bladelab.runner.kernel.forces`) and the implicit one
(:func:`bladelab.runner.implicit.implicit_forces`)."""

from __future__ import annotations

import math

from numba import njit

from bladelab.numba_cache import refresh_stale_caches
from bladelab.runner.layout import CP_AZ, CP_RADIUS, CP_SITE


@njit(cache=True, _nrt=False)  # no reference counting (bladelab.runner.kernel)
def lowest_point(cp, c, site_xpos, site_xmat):
    """``(px, py, pz, depth)`` [m] of contact ``c``: the lowest point of its ellipse
    (semi-axes ``ax``, ``az`` in its site's x–z plane; a sphere when equal) and its depth below
    the ground (negative above it). ``site_xmat`` may be empty (no oriented sites: a sphere)."""
    site = int(cp[c, CP_SITE])
    ax = cp[c, CP_RADIUS]
    az = cp[c, CP_AZ]
    if site_xmat.shape[0] > 0:
        exx, exz = site_xmat[site, 0], site_xmat[site, 6]  # site x axis (world x, z)
        ezx, ezz = site_xmat[site, 2], site_xmat[site, 8]  # site z axis
    else:
        exx, exz, ezx, ezz = 1.0, 0.0, 0.0, 1.0
    h = math.sqrt((ax * exz) ** 2 + (az * ezz) ** 2)
    ct = -ax * exz / h
    st = -az * ezz / h
    px = site_xpos[site, 0] + ax * ct * exx + az * st * ezx
    py = site_xpos[site, 1]
    pz = site_xpos[site, 2] - h
    return px, py, pz, h - site_xpos[site, 2]


refresh_stale_caches(globals())
