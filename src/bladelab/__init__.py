"""bladelab: biomechanics of running-specific prostheses.

Three workflows, one per source document:

- **characterise**: how stiff and how damped is a blade in real sprinting (``bladelab.trial``,
  ``bladelab.blade``, ``bladelab.sim``, ``bladelab.identify``);
- **predict**: which stiffness category lets an athlete run fastest or cheapest
  (``bladelab.runner``);
- **design**: how blade shape and stiffness change performance and safety
  (``bladelab.design``).

SI units inside (m, s, N, rad, N·m/rad); literature units (N·m/deg) only at the edges, converted
by :mod:`bladelab.units`.
"""

from bladelab.errors import BladelabError

__version__ = "0.1.0"

__all__ = ["BladelabError", "__version__"]
