# SPDX-License-Identifier: MIT
"""Results for visualisation: cell-averaged stress, von Mises norm, XDMF time series.

Quadrature-point stresses cannot be written to XDMF directly; they are averaged per cell with the
rule's weights (exact for the paper's one-point P1/P0 pairing) into a DG0 tensor field.
"""

from __future__ import annotations

from pathlib import Path
from typing import Optional

import basix
import numpy as np
import ufl
from dolfinx import fem, io
from dolfinx import mesh as dmesh
from mpi4py import MPI

from vpcontact.kernels.mandel import from_mandel
from vpcontact.model.quadrature import QuadratureState

def von_mises(m: np.ndarray, dim: int, s33: np.ndarray | None = None) -> np.ndarray:
    """√(3/2 s:s) of Mandel stresses (2-D: σ33 = ``s33``, zero in plane stress; 1-D: |σ|)."""
    t = from_mandel(m, dim)
    full = np.zeros((m.shape[0], 3, 3))
    full[:, :dim, :dim] = t
    if s33 is not None:
        full[:, 2, 2] = s33
    dev = full - np.trace(full, axis1=1, axis2=2)[:, None, None] * np.eye(3) / 3.0
    return np.sqrt(1.5 * np.einsum("nij,nij->n", dev, dev))


class CellStress:
    """DG0 fields of the cell-averaged stress tensor and its von Mises norm."""

    def __init__(self, state: QuadratureState, out_of_plane=None, correction=None):
        self.state = state
        self._out_of_plane = out_of_plane  # () -> σ33 per point (plane strain) or None
        # () -> what the formulation adds to each normal stress per point (the mixed
        # formulation's p − m_q), or None (σ_h = σ_q)
        self._correction = correction
        mesh = state.stress.function_space.mesh
        dim = state.dim
        self.stress = fem.Function(fem.TensorFunctionSpace(mesh, ("DG", 0), shape=(dim, dim)),
                                   name="stress")
        self.von_mises = fem.Function(fem.FunctionSpace(mesh, ("DG", 0)), name="von_mises")
        cell_type = basix.cell.string_to_type(mesh.ufl_cell().cellname())
        _, weights = basix.make_quadrature(basix.QuadratureType.Default, cell_type, state.degree)
        self._weights = weights / weights.sum()
        num_cells = state.num_cells
        q_dofs = state.stress.function_space.dofmap.list.array.reshape(num_cells, -1)
        self._q_dofs = q_dofs
        #: the DG0 dof of each cell (owned and ghost), in the cells' order
        self.dg_dofs = self.von_mises.function_space.dofmap.list.array.reshape(num_cells)

    @classmethod
    def of(cls, problem) -> "CellStress":
        """The cell stress of ``problem`` (its σ33 in plane strain, its formulation's
        correction of the normal stresses)."""
        return cls(problem.state, getattr(problem.law, "out_of_plane_stress", None),
                   problem.stress_correction_at_points)

    def mean(self, values: np.ndarray) -> np.ndarray:
        """Per cell the rule-weighted mean ``(cells, n)`` of quadrature-point ``values``
        ``(points, n)`` (in the quadrature space's dof order)."""
        return np.einsum("q,cqn->cn", self._weights, values[self._q_dofs])

    def update(self) -> None:
        """Recompute both fields from the current quadrature stress."""
        st = self.state
        dim = st.dim
        values = st.view(st.stress)[self._q_dofs]                 # (cells, points, n)
        added = self._correction() if self._correction is not None else None
        if added is not None:
            added = added.reshape(-1)[self._q_dofs]
            values = values.copy()
            values[..., :dim] += added[..., None]
        mean = np.einsum("q,cqn->cn", self._weights, values)
        self.stress.x.array.reshape(-1, dim * dim)[self.dg_dofs] = \
            from_mandel(mean, dim).reshape(-1, dim * dim)
        s33 = None
        if self._out_of_plane is not None and len(self._out_of_plane()) == st.num_points:
            s33_points = self._out_of_plane()[self._q_dofs]
            if added is not None:
                s33_points = s33_points + added
            s33 = np.einsum("q,cq->c", self._weights, s33_points)
        self.von_mises.x.array[self.dg_dofs] = von_mises(mean, dim, s33)


class XdmfSeries:
    """XDMF time series (for ParaView) of displacement, stress and von Mises norm."""

    def __init__(self, path: str | Path, u: fem.Function, cell_stress: CellStress, extra=(),
                 append: bool = False):
        mesh = u.function_space.mesh
        self.u = u
        self.extra = list(extra)  # (Function, refresh()) written after the built-in fields
        self.cells = cell_stress
        self._u_out = u
        degree = u.function_space.ufl_element().degree()
        if degree != 1:  # XDMF needs fields of the geometry's degree
            V1 = fem.VectorFunctionSpace(mesh, ("Lagrange", 1), dim=mesh.geometry.dim)
            self._u_out = fem.Function(V1, name="displacement")
        self.skip: set[float] = set()  # times already in the file (a resumed run's)
        #: where an unreadable series of a run that died was set aside (None: it was not)
        self.set_aside: Optional[Path] = None
        self.file = None
        if append and Path(path).is_file():
            self.skip = written_times(path, mesh.comm)
            self.file = _open_to_append(path, mesh.comm)
            if self.file is None:
                # A run killed while writing leaves its HDF5 file unreadable (a zeroed header):
                # keep it aside for what can be recovered, and start the series afresh.
                self.set_aside, self.skip = _set_aside(Path(path), mesh.comm), set()
        if self.file is None:
            self.file = io.XDMFFile(mesh.comm, str(path), "w")
            self.file.write_mesh(mesh)

    def write(self, t: float) -> None:
        if any(abs(t - s) <= 1e-9 * max(1.0, abs(t)) for s in self.skip):
            return  # a resumed run recomputes the steps after its checkpoint: already written
        if self._u_out is not self.u:
            self._u_out.interpolate(self.u)
        self.cells.update()
        self.file.write_function(self._u_out, t)
        self.file.write_function(self.cells.stress, t)
        self.file.write_function(self.cells.von_mises, t)
        for function, refresh in self.extra:
            refresh()
            self.file.write_function(function, t)

    def close(self) -> None:
        self.file.close()


def on_rank0(comm, action) -> None:
    """Run ``action`` (which writes a file) on rank 0; every rank returns once it is done, or
    raises OSError if it failed (so that no rank is left waiting for the others)."""
    failure = None
    if comm.rank == 0:
        try:
            action()
        except OSError as err:
            failure = str(err)
    failure = comm.bcast(failure, root=0)
    if failure is not None:
        raise OSError(failure)


#: the 8 bytes an HDF5 file's superblock starts with (at 0, or after a user block of 512·2ⁿ)
HDF5_SIGNATURE = b"\x89HDF\r\n\x1a\n"


def _has_hdf5_signature(path: Path) -> bool:
    """Whether ``path`` holds an HDF5 superblock where the format puts one (0, 512, 1024, …)."""
    try:
        size = path.stat().st_size
        with open(path, "rb") as f:
            offset = 0
            while offset + len(HDF5_SIGNATURE) <= size:
                f.seek(offset)
                if f.read(len(HDF5_SIGNATURE)) == HDF5_SIGNATURE:
                    return True
                offset = 512 if offset == 0 else 2 * offset
    except OSError:
        return False
    return False


def _open_to_append(path: Path, comm) -> Optional[io.XDMFFile]:
    """The XDMF file opened to append to, or None (on every rank) where it cannot be. A data
    file without an HDF5 superblock (a run killed while writing it) is not handed to HDF5,
    which would print its error stack to stderr before refusing it."""
    readable = comm.bcast(_has_hdf5_signature(Path(path).with_suffix(".h5")) if comm.rank == 0
                          else None, root=0)
    if not readable:
        return None
    try:
        file = io.XDMFFile(comm, str(path), "a")
    except RuntimeError:
        file = None
    if comm.allreduce(file is None, op=MPI.LOR):
        if file is not None:
            file.close()
        return None
    return file


def _set_aside(path: Path, comm) -> Path:
    """Rename the series ``path`` (.xdmf and .h5) to the first free ``<stem>.broken<n>``; the
    new .xdmf's name (collective)."""
    new = None
    if comm.rank == 0:
        n = 1
        while any(path.with_name(f"{path.stem}.broken{n}{s}").exists() for s in (".xdmf", ".h5")):
            n += 1
        new = path.with_name(f"{path.stem}.broken{n}.xdmf")
    new = comm.bcast(new, root=0)
    on_rank0(comm, lambda: [p.rename(new.with_suffix(p.suffix)) for p in
                            (path, path.with_suffix(".h5")) if p.exists()])
    return new


def written_times(path: str | Path, comm) -> set[float]:
    """The times of the grids in an XDMF time series (read on rank 0)."""
    times = None
    if comm.rank == 0:
        import xml.etree.ElementTree as ElementTree
        try:
            root = ElementTree.parse(path).getroot()
            times = {float(e.get("Value")) for e in root.iter("Time")}
        except (OSError, ElementTree.ParseError, TypeError, ValueError):
            times = set()
    return comm.bcast(times, root=0)


class ContactHistory:
    """u_ν, gap and nodal σ_ν at the nodes of every contact part over time, gathered on rank 0
    (part by part, in the problem's order; ``part`` holds each node's part index).

    The history keeps the model's normal stress σ_ν (negative in compression); what it writes
    and draws is the contact pressure p = −σ_ν (positive in compression, as contact codes
    report it): :attr:`pressure`.

    Args:
        problem: the problem.
        parts: the contact parts to record (default: all of the problem's).
    """

    def __init__(self, problem, parts=None):
        self.parts = list(problem.contacts if parts is None else parts)
        if not self.parts:
            raise ValueError("the problem has no contact part")
        self.problem = problem
        self.comm = problem.mesh.comm
        self.names = [p.name for p in self.parts]
        self.bounded = [p.bounded for p in self.parts]
        self.points = self._gathered(lambda p: p.nodes.points)
        self.gap = self._gathered(lambda p: p.nodes.gap)  # at t = 0
        self.part = self._gathered(lambda p: np.full(len(p.nodes.gap), self.parts.index(p)))
        self.gaps: list[np.ndarray] = []      # at each recorded time (obstacles may move)
        self.times: list[float] = []
        self.normal_displacement: list[np.ndarray] = []
        self.normal_stress: list[np.ndarray] = []   # σ_ν per node (the model's sign)
        #: what the parts report at their nodes beyond u_ν, gap and σ_ν (each kind once, in
        #: the parts' order; a part without one reports zeros), and its records
        self.outputs = _merged(p.nodal_outputs() for p in self.parts)
        self.records: dict[str, list[np.ndarray]] = {o.key: [] for o in self.outputs}

    def _gathered(self, value) -> np.ndarray:
        """``value(part)`` of every part, gathered on rank 0 and joined part after part."""
        arrays = [_gather(self.comm, value(p)) for p in self.parts]
        return np.concatenate(arrays) if self.comm.rank == 0 else np.zeros(0)

    def unreachable(self) -> list[int]:
        """Per part, the nodes whose normal rays missed the obstacle at t = 0 (collective)."""
        return [self.comm.allreduce(0 if p.nodes.unreachable is None
                                    else int(np.count_nonzero(p.nodes.unreachable)))
                for p in self.parts]

    def record(self, t: float) -> None:
        un = self._gathered(lambda p: p.nodes.normal_displacement(self.problem.u))
        normal_stress = self._gathered(lambda p: p.pressure())   # σ_ν
        gap = self._gathered(lambda p: p.nodes.gap)
        extra = {key: self._gathered(lambda p, key=key: nodal_values(p, key))
                 for key in self.records}
        if self.comm.rank == 0:
            self.gaps.append(gap)
            self.times.append(t)
            self.normal_displacement.append(un)
            self.normal_stress.append(normal_stress)
            for key, values in extra.items():
                self.records[key].append(values)

    def restore(self, arrays: dict) -> None:
        """The records of a checkpoint (:mod:`vpcontact.output.checkpoint`), on rank 0."""
        if self.comm.rank != 0 or "times" not in arrays:
            return
        self.times = [float(t) for t in arrays["times"]]
        if self.times:
            self.normal_displacement = list(arrays["un"])
            self.normal_stress = list(arrays["pressure"])   # (σ_ν, as checkpoints hold it)
            self.gaps = list(arrays["gap"])
            self.records = {key: list(arrays[key]) for key in self.records}

    def closest_approach(self, index: int = 0) -> Optional[dict]:
        """For the part ``index``: whether it ever touched after the initial state (normal
        compliance: a compressive pressure, which is exactly 0 off contact; Signorini, whose
        inactive nodes carry round-off pressures: a clearance within 1e-10 max(1, |g|) of zero,
        the VI's active set), and the
        smallest clearance gap − u_ν over the run with its time and node (rank 0; None elsewhere
        or without records)."""
        at = np.flatnonzero(self.part == index) if self.comm.rank == 0 else []
        if self.comm.rank != 0 or not self.times or not len(at):
            return None
        clearance = (np.array(self.gaps) - np.array(self.normal_displacement))[:, at]
        solved = slice(1, None)  # the records after the initial state's
        if self.bounded[index]:
            scale = max(1.0, float(np.abs(np.array(self.gaps)[:, at]).max()))
            touched = bool((clearance[solved] <= 1e-10 * scale).any())
        else:
            touched = bool((np.array(self.normal_stress)[solved, at] < 0).any())
        k, i = np.unravel_index(int(np.argmin(clearance)), clearance.shape)
        return {"touched": touched, "clearance": float(clearance[k, i]),
                "time": float(self.times[k]), "point": self.points[at[i]].tolist()}

    @property
    def pressure(self) -> list[np.ndarray]:
        """The contact pressure p = −σ_ν per node at each recorded time (rank 0): positive
        in compression, zero off contact (``0 − σ_ν``: no negative zeros)."""
        return [0.0 - s for s in self.normal_stress]

    def write_csv(self, path: str | Path) -> None:
        """Long format: t, x, y, z, u_normal, gap, clearance, pressure (p = −σ_ν, positive in
        compression; and, with several
        contact parts, part: the boundary part's name), written by rank 0; the file is on disk
        when any rank returns. ``gap`` is the obstacle's distance from the node's reference
        position along its normal (it changes when the obstacle moves), ``clearance`` =
        gap − u_normal the current one (0 where the node touches)."""
        several = len(self.parts) > 1
        header = "".join(f",{o.column}" + (f",{o.running}" if o.running else "")
                         for o in self.outputs)

        def write():
            names = [f",{self.names[i]}" if several else "" for i in self.part]
            sums = {o.key: np.zeros(len(self.points)) for o in self.outputs if o.running}
            with open(path, "w") as f:
                f.write("t,x,y,z,u_normal,gap,clearance,pressure" + header
                        + (",part" if several else "") + "\n")
                for k, (t, un, gap, p) in enumerate(zip(self.times, self.normal_displacement,
                                                        self.gaps, self.pressure)):
                    extra = self._csv_cells(k, sums)
                    for (x, y, z), u_i, g_i, p_i, e, name in zip(self.points, un, gap, p, extra,
                                                                 names):
                        f.write(f"{t:.10g},{x:.10g},{y:.10g},{z:.10g},"
                                f"{u_i:.10e},{g_i:.10e},{g_i - u_i:.10e},{p_i:.10e}{e}{name}\n")
        on_rank0(self.comm, write)

    def _csv_cells(self, k: int, sums: dict) -> list[str]:
        """The record ``k``'s cells of :attr:`outputs` per node (``sums``: the running sums,
        advanced by this record)."""
        cells = [""] * len(self.points)
        for o in self.outputs:
            values = self.records[o.key][k]
            if o.running:
                sums[o.key] += values
            columns = [values] + ([sums[o.key]] if o.running else [])
            for column in columns:
                text = ([f",{int(v)}" for v in column] if o.integer
                        else [f",{v:.10e}" for v in column])
                cells = [a + b for a, b in zip(cells, text)]
        return cells


def _merged(outputs) -> tuple:
    """The :class:`~vpcontact.model.contact.NodalOutput` s of several parts, each key once."""
    merged = {}
    for group in outputs:
        for o in group:
            merged.setdefault(o.key, o)
    return tuple(merged.values())


def nodal_values(part, key: str) -> np.ndarray:
    """The output ``key`` at the nodes of ``part`` (this rank): the part's, or zeros where the
    part does not report it."""
    if any(o.key == key for o in part.nodal_outputs()):
        return part.nodal_values(key)
    return np.zeros(len(part.nodes.gap))


def _gather(comm, array: np.ndarray) -> np.ndarray:
    parts = comm.gather(np.asarray(array), root=0)
    return np.concatenate(parts) if comm.rank == 0 else np.zeros(0)


def deformed_cells(u: fem.Function, values: fem.Function):
    """Vertex coordinates of the deformed owned cells and a DG0 value per cell, on rank 0.

    Returns (cells (N, vertices, gdim) of x + u, values (N,)) on rank 0 and (None, None) elsewhere.
    """
    mesh = u.function_space.mesh
    tdim, gdim = mesh.topology.dim, mesh.geometry.dim
    cell_type = basix.cell.string_to_type(mesh.ufl_cell().cellname())
    ref = basix.geometry(cell_type)
    owned = np.arange(mesh.topology.index_map(tdim).size_local, dtype=np.int32)
    x_expr = fem.Expression(ufl.SpatialCoordinate(mesh) + u, ref)
    coords = x_expr.eval(owned).reshape(len(owned), len(ref), gdim)
    dg = values.function_space.dofmap.list.array.reshape(-1)[:len(owned)]
    local_values = values.x.array[dg]
    all_coords = _gather(mesh.comm, coords)
    all_values = _gather(mesh.comm, local_values)
    return (all_coords, all_values) if mesh.comm.rank == 0 else (None, None)


def boundary_faces(u: fem.Function, values: fem.Function):
    """Deformed exterior facets (x + u) of a 3-D mesh with their cell's DG0 value, on rank 0."""
    mesh = u.function_space.mesh
    tdim, gdim = mesh.topology.dim, mesh.geometry.dim
    mesh.topology.create_connectivity(tdim - 1, tdim)
    mesh.topology.create_connectivity(tdim, tdim - 1)
    f2c = mesh.topology.connectivity(tdim - 1, tdim)
    c2f = mesh.topology.connectivity(tdim, tdim - 1)
    n_owned = mesh.topology.index_map(tdim).size_local
    facets = dmesh.exterior_facet_indices(mesh.topology)
    cells = np.array([f2c.links(f)[0] for f in facets], dtype=np.int32).reshape(-1)
    keep = cells < n_owned
    facets, cells = facets[keep], cells[keep]
    local_facet = np.array([np.flatnonzero(c2f.links(c) == f)[0] for f, c in zip(facets, cells)],
                           dtype=np.int32)
    cell_type = basix.cell.string_to_type(mesh.ufl_cell().cellname())
    ref = basix.geometry(cell_type)
    facet_vertices = np.array(basix.topology(cell_type)[tdim - 1])   # (facets per cell, vertices)
    x_expr = fem.Expression(ufl.SpatialCoordinate(mesh) + u, ref)
    corners = x_expr.eval(cells).reshape(len(cells), len(ref), gdim)
    faces = corners[np.arange(len(cells))[:, None], facet_vertices[local_facet]]
    dg = values.function_space.dofmap.list.array.reshape(-1)
    all_faces = _gather(mesh.comm, faces)
    all_values = _gather(mesh.comm, values.x.array[dg[cells]])
    return (all_faces, all_values) if mesh.comm.rank == 0 else (None, None)
