"""Physical constants: each defined once, here.

Models whose source fixes another value (the runner of seed 001 was built with g = 9.81 m/s²)
carry it as a model parameter in their own data file, not as a second constant.
"""

from __future__ import annotations

STANDARD_GRAVITY = 9.80665  # m/s², standard acceleration of gravity (ISO 80000-3)

__all__ = ["STANDARD_GRAVITY"]
