"""Finding a gait for a runner model (:mod:`bladelab.runner`): the predict wing.

- :mod:`bladelab.predict.reflex`: seed 001's method, a reflex controller whose parameters CMA-ES
  tunes on forward simulations (controller, objective, optimisation, category sweeps).
- :mod:`bladelab.predict.collocation`: direct collocation of one periodic stride (CasADi + IPOPT).
"""
