"""bladelab: biomechanics of running-specific prostheses.

Three workflows, one per source document (the guides in ``docs/guide-*.md`` say how to run them
and how far each is validated):

- **characterise**: how stiff and how damped is a blade in real sprinting. Trials and stances
  (``bladelab.trial``), blades (``bladelab.blade``), the blade simulation (``bladelab.sim``),
  identification of K* and D* (``bladelab.identify``), studies (``bladelab.study``), stance
  mechanics and group statistics (``bladelab.mechanics``, ``bladelab.stats``);
- **predict**: which stiffness category lets an athlete run fastest or cheapest. The runner
  models (``bladelab.runner``) and the two ways of finding their gaits (``bladelab.predict``:
  ``reflex`` controller + CMA-ES, ``collocation`` of one periodic stride);
- **design**: how blade shape and stiffness change performance and safety (``bladelab.design``).

``bladelab.report`` writes the HTML reports of all three, ``bladelab.example`` the synthetic
example study, ``bladelab.datasets`` finds the measured data the package ships, and
``bladelab.cli`` is the command line. ``docs/architecture.md`` draws how the wings import one
another.

SI units inside (m, s, N, rad, N·m/rad); literature units (N·m/deg) only at the edges, converted
by :mod:`bladelab.units`.
"""

from bladelab.errors import BladelabError

__version__ = "0.1.0"

__all__ = ["BladelabError", "__version__"]
