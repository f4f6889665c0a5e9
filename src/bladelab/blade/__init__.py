"""Blades: profiles, segmentation, blade specs and the built-in catalogue.

``load_blade("xtreme-cat5").build()`` gives the :class:`BladeModel` that simulation engines
consume; ``list_blades()`` names the built-ins; ``docs/blade-spec.md`` documents the spec files.
"""

from bladelab.blade.catalogue import blade_catalogue, list_blades, load_blade, multilink_blade
from bladelab.blade.model import BladeModel, CompliantJoint, ContactModel, SoleEllipse
from bladelab.blade.plot import plot_blade, save_blade_figure
from bladelab.blade.profile import (
    Profile,
    ProfileElement,
    find_self_intersections,
    profile_from_elements,
    read_profile_csv,
)
from bladelab.blade.segmentation import (
    Segmentation,
    segment_profile,
    segmentation_error,
    write_segmentation_json,
)
from bladelab.blade.spec import BladeSpec, read_blade_spec, segment_mass_properties

__all__ = [
    "BladeModel",
    "BladeSpec",
    "CompliantJoint",
    "ContactModel",
    "Profile",
    "ProfileElement",
    "Segmentation",
    "SoleEllipse",
    "blade_catalogue",
    "find_self_intersections",
    "list_blades",
    "load_blade",
    "multilink_blade",
    "plot_blade",
    "profile_from_elements",
    "read_blade_spec",
    "read_profile_csv",
    "save_blade_figure",
    "segment_mass_properties",
    "segment_profile",
    "segmentation_error",
    "write_segmentation_json",
]
