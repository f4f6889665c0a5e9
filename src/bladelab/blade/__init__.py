"""Blades: profiles, segmentation, blade specs and the built-in catalogue."""

from bladelab.blade.model import BladeModel, CompliantJoint, ContactModel, SoleEllipse

__all__ = ["BladeModel", "CompliantJoint", "ContactModel", "SoleEllipse"]
