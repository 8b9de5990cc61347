# SPDX-License-Identifier: MIT
"""The viscoplastic strain ε_vp = ε(u) − E⁻¹σ and its equivalent, per cell (for the XDMF series
and ``probes.csv``).

The laws integrate σ̇ = E ε̇(u) + G(σ, ε), so ε_vp = ε − E⁻¹σ is the part of the strain that the
stress does not account for elastically: ε̇_vp = −E⁻¹G (Perzyna: (σ − P_K σ)/μ*; the linear law
aσ + bε: its inelastic strain). E is the law's own elasticity matrix
(:meth:`vpcontact.model.constitutive.Elasticity.matrix`, the kernels' moduli), σ the kernels'
quadrature-point stress σ_q: in the mixed formulation σ_h = σ_q + (p − m_q)·1 differs from σ_q
by a mean stress only, and σ_q's volumetric part is the kernels' K tr ε, so ε_vp comes out
deviatoric, as the isochoric flow makes it. With an initial state (u_0, σ_0) ε_vp starts at
ε(u_0) − E⁻¹σ_0 (zero for an unstressed body at rest).

The equivalent viscoplastic strain is von Mises' ε_eq = √(2/3 dev ε_vp : dev ε_vp) of the current
ε_vp (the uniaxial strain that a bar's isochoric flow would give), not the accumulated
∫ √(2/3 ε̇_vp : ε̇_vp) dt: the laws carry no hardening and no accumulated-strain variable, and the
current one is a function of the state (so that a resumed run writes the same numbers as an
uninterrupted one). Under monotonic proportional flow the two are equal. The tensor is the
model's: 3-D; plane strain with its ε_vp,33 = −(E⁻¹σ)_33 (ε33 = 0); plane stress its in-plane
components (the 2-D model has no ε_vp,33); 1-D ε_eq = |ε_vp|.
"""

from __future__ import annotations

from typing import Optional

import numpy as np
from dolfinx import fem

from vpcontact.kernels.mandel import from_mandel
from vpcontact.output.fields import CellStress

#: Mandel size -> dimension of the tensors
_DIMENSION = {1: 1, 3: 2, 6: 3}


def equivalent_strain(tensors: np.ndarray) -> np.ndarray:
    """von Mises' equivalent strain √(2/3 dev e : dev e) of symmetric tensors ``(N, d, d)``
    (d = 2: the in-plane components, the 33 one zero); for d = 1 the uniaxial |e|."""
    d = tensors.shape[1]
    if d == 1:
        return np.abs(tensors[:, 0, 0])
    full = np.zeros((tensors.shape[0], 3, 3))
    full[:, :d, :d] = tensors
    dev = full - np.trace(full, axis1=1, axis2=2)[:, None, None] * np.eye(3) / 3.0
    return np.sqrt(2.0 / 3.0 * np.einsum("nij,nij->n", dev, dev))


class ViscoplasticStrain:
    """DG0 fields of the cell-averaged ε_vp (``viscoplastic_strain``, a d×d tensor) and its
    equivalent (``equivalent_viscoplastic_strain``), averaged with the rule's weights as the
    stress is (:class:`~vpcontact.output.fields.CellStress`).

    Args:
        cells: the cell stress (its mesh, state and averaging).
        law: the problem's law: its ``elasticity`` and, where the law keeps an out-of-plane
            stress (plane strain), its ``full_history`` (the 3-D stress and strain).
    """

    def __init__(self, cells: CellStress, law):
        self.cells = cells
        self.state = cells.state
        self._compliance = np.linalg.inv(law.elasticity.matrix())  # E⁻¹ (Mandel)
        self._full = getattr(law, "full_history", None)
        mesh = self.state.stress.function_space.mesh
        dim = self.state.dim
        self.tensor = fem.Function(
            fem.TensorFunctionSpace(mesh, ("DG", 0), shape=(dim, dim)), name="viscoplastic_strain")
        self.equivalent = fem.Function(fem.FunctionSpace(mesh, ("DG", 0)),
                                       name="equivalent_viscoplastic_strain")

    @classmethod
    def of(cls, problem, cells: CellStress) -> Optional["ViscoplasticStrain"]:
        """The fields of ``problem``'s law, or None for a law without an elasticity."""
        if getattr(problem.law, "elasticity", None) is None:
            return None
        return cls(cells, problem.law)

    def at_points(self) -> np.ndarray:
        """ε_vp = ε − E⁻¹σ (Mandel, in the law's own size: 6 in plane strain) at every
        quadrature point of the committed state."""
        st = self.state
        stress, strain = st.view(st.stress_old), st.view(st.strain_old)
        if self._full is not None:
            stress, strain = self._full(stress, strain)
        return strain - stress @ self._compliance.T

    def update(self) -> None:
        """Recompute both fields from the committed state."""
        mean = self.cells.mean(self.at_points())
        tensors = from_mandel(mean, _DIMENSION[mean.shape[1]])
        dim = self.state.dim
        dofs = self.cells.dg_dofs
        self.tensor.x.array.reshape(-1, dim * dim)[dofs] = \
            tensors[:, :dim, :dim].reshape(-1, dim * dim)
        self.equivalent.x.array[dofs] = equivalent_strain(tensors)

    def xdmf_fields(self) -> list:
        """(Function, refresh) pairs for :class:`~vpcontact.output.fields.XdmfSeries`."""
        return [(self.tensor, self.update), (self.equivalent, lambda: None)]
