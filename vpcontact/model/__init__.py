# SPDX-License-Identifier: MIT
"""Stage 2, the model: the physics of one time step, as UFL terms and C++ kernel calls.

Takes material data, boundary tags and contact data; gives the pieces the solver assembles:

* :mod:`.constitutive`: the laws σ̇ = E ε(u̇) + G(σ, ε(u)) (elastic, Perzyna with the
  energy-norm projection P_K, linear G = aσ + bε, plane strain) and their time-discrete
  stress updates, evaluated at quadrature points by :mod:`vpcontact.kernels` (C++);
* :mod:`.quadrature`: the stress, strain and tangent stored at quadrature points;
* :mod:`.tensors`: UFL helpers for symmetric tensors stored as Mandel vectors;
* contact conditions on Γ3 (the parts' protocol: :mod:`.contact`): :mod:`.normal_compliance`
  (a deformable foundation, a UFL boundary term) and :mod:`.signorini` (a rigid one: bounds of
  a variational inequality; its parts in :mod:`.signorini_part`, the monitor of the contact
  pressure in :mod:`.contact_monitor`), with rigid obstacles as level sets that may translate
  and turn (:mod:`.obstacle`); the contact nodes, their normals and gaps to an obstacle in
  :mod:`.contact_nodes`; Coulomb and Tresca friction, composed by the parts, in
  :mod:`.friction` and :mod:`.nodal_friction`.
"""

from vpcontact.model.constitutive import Elastic, Elasticity, LinearRate, Perzyna, PlaneStrain
from vpcontact.model.normal_compliance import NormalCompliance
from vpcontact.model.obstacle import LevelSet, gap_along_normal, rotation_matrix
from vpcontact.model.quadrature import QuadratureState
from vpcontact.model.contact_monitor import ContactMonitor
from vpcontact.model.contact_nodes import (ContactDofs, ContactReport, Surface, contact_dofs,
                                           variable_bounds)
from vpcontact.model.signorini import Signorini

__all__ = ["ContactDofs", "ContactMonitor", "ContactReport", "Elastic", "Elasticity", "LevelSet",
           "LinearRate", "NormalCompliance", "Perzyna", "PlaneStrain", "QuadratureState",
           "Signorini", "Surface", "contact_dofs", "gap_along_normal", "rotation_matrix", "variable_bounds"]
