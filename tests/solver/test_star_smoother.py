# SPDX-License-Identifier: MIT
"""The vertex-star smoother of the p-multigrid cycle: the C++ patch solves against dense
numpy solves, the stars of P2 spaces, and the sweep as a smoother of an elasticity matrix
(serially and on 2 ranks)."""

import numpy as np
import pytest
import ufl
from dolfinx import fem
from dolfinx import mesh as dmesh
from dolfinx.fem import petsc as fem_petsc
from mpi4py import MPI

from vpcontact import _cpp
from vpcontact.errors import SolverOptionError
from vpcontact.solver.pc import star_smoother
from tests.support import flowing_beam

COMM = MPI.COMM_WORLD


def _csr(A):
    rows, cols = np.nonzero(A)
    return (np.searchsorted(rows, np.arange(A.shape[0] + 1)).astype(np.int64),
            cols.astype(np.int64), A[rows, cols])


def _patches():
    offsets = np.array([0, 10, 22, 30], dtype=np.int64)
    indices = np.concatenate([np.arange(0, 10), np.arange(8, 20)[::-1], np.arange(18, 26)])
    return offsets, indices.astype(np.int64)


def _matrix(n=30, seed=0):
    rng = np.random.default_rng(seed)
    A = rng.standard_normal((n, n))
    A[np.abs(A) < 1.0] = 0.0  # sparse, not symmetric
    return A + 6.0 * np.eye(n)


@pytest.mark.serial
def test_patch_solves_equal_dense_solves():
    A = _matrix()
    offsets, indices = _patches()
    patches = [indices[offsets[p]:offsets[p + 1]] for p in range(3)]
    smoother = _cpp.PatchSmoother(offsets, indices, 30)
    smoother.factorize(*_csr(A))
    b = np.random.default_rng(1).standard_normal(30)

    y = np.zeros(30)
    smoother.apply(b, y, 0.5)
    expected = np.zeros(30)
    for I in patches:
        expected[I] += 0.5 * np.linalg.solve(A[np.ix_(I, I)], b[I])
    assert np.allclose(y, expected, rtol=0, atol=1e-13)

    assert smoother.singular == 0 and smoother.size == 3


@pytest.mark.serial
def test_a_singular_patch_is_smoothed_by_its_diagonal():
    A = _matrix()
    A[3, :10] = 0.0  # patch 0's block has a zero row: singular
    A[3, 3] = 0.0
    A[4, 4] = 5.0
    offsets, indices = _patches()
    smoother = _cpp.PatchSmoother(offsets, indices, 30)
    smoother.factorize(*_csr(A))
    assert smoother.singular == 1
    b = np.ones(30)
    y = np.zeros(30)
    smoother.apply(b, y, 1.0)
    assert y[3] == 0.0 and y[4] == pytest.approx(1.0 / 5.0)  # (row 4 lies in patch 0 only)
    assert np.isfinite(y).all()


@pytest.mark.serial
@pytest.mark.parametrize("offsets, indices, message", [
    ([0, 2, 5], [0, 1, 2, 3], "offsets: must rise from 0"),
    ([0, 2], [0, 30], "indices: 30 is not a local row"),
    ([0, 3], [4, 5, 4], "indices: row 4 repeated in patch 0"),
])
def test_bad_patches_are_refused(offsets, indices, message):
    with pytest.raises(ValueError, match=message):
        _cpp.PatchSmoother(np.array(offsets), np.array(indices), 30)


@pytest.mark.serial
def test_a_patch_smoother_refuses_another_size_and_an_unfactorized_apply():
    offsets, indices = _patches()
    smoother = _cpp.PatchSmoother(offsets, indices, 30)
    with pytest.raises(ValueError, match="factorize a matrix before"):
        smoother.apply(np.ones(30), np.zeros(30), 0.5)
    with pytest.raises(ValueError, match="A: 31 rows, the patches have 30"):
        smoother.factorize(*_csr(_matrix(31)))
    smoother.factorize(*_csr(_matrix()))
    with pytest.raises(ValueError, match="r: expected shape"):
        smoother.apply(np.ones(29), np.zeros(30), 0.5)


def _p2_space(dim):
    if dim == 2:
        msh = dmesh.create_unit_square(COMM, 6, 5)
    else:
        msh = dmesh.create_box(COMM, [np.zeros(3), np.array([2.0, 1.0, 1.0])], [4, 2, 3])
    return fem.FunctionSpace(msh, ufl.VectorElement("Lagrange", msh.ufl_cell(), 2))


@pytest.mark.parametrize("dim", [2, 3])
def test_vertex_stars_of_p2_hold_a_vertex_and_its_edge_midpoints(dim):
    """A star per vertex (on 2 ranks, a vertex at the partition's edge may have one on each,
    with each process's own unknowns); its unknowns: the vertex's and those of the midpoints
    of the edges around it (the ones this process owns), every component; every owned unknown
    in a star: a vertex's in exactly its own, an edge midpoint's in at most two."""
    V = _p2_space(dim)
    msh = V.mesh
    offsets, indices = star_smoother.vertex_stars(V)
    vertex_map = msh.topology.index_map(0)
    stars = COMM.allreduce(len(offsets) - 1, op=MPI.SUM)
    assert vertex_map.size_global <= stars <= vertex_map.size_global + COMM.allreduce(
        vertex_map.num_ghosts, op=MPI.SUM)
    assert np.all(np.diff(offsets) > 0)
    bs = V.dofmap.index_map_bs
    owned = V.dofmap.index_map.size_local * bs
    assert indices.min() >= 0 and indices.max() < owned
    counts = np.bincount(indices, minlength=owned)
    assert counts.min() >= 1  # every owned unknown is smoothed
    # the nodes at the vertices and at the edges' midpoints
    msh.topology.create_connectivity(1, 0)
    edge_vertices = msh.topology.connectivity(1, 0)
    node_of = lambda d, entities: fem.locate_dofs_topological(  # noqa: E731
        V, d, entities, remote=False)  # (local: the loop below differs between processes)
    vertex_nodes = node_of(0, np.arange(vertex_map.size_local, dtype=np.int32))
    vertex_nodes = vertex_nodes[vertex_nodes < V.dofmap.index_map.size_local]
    assert np.all(counts[vertex_nodes * bs] == 1)
    assert counts.max() <= 2
    # one star in full: an owned vertex and the owned midpoints of its edges
    msh.topology.create_connectivity(0, 1)
    v = 0
    edges = msh.topology.connectivity(0, 1).links(v)
    midpoints = [np.setdiff1d(node_of(1, np.array([e], dtype=np.int32)),  # (the closure's
                              node_of(0, edge_vertices.links(e)))  # nodes, less the ends')
                 for e in edges]
    expected_nodes = np.concatenate([node_of(0, np.array([v], dtype=np.int32)), *midpoints])
    expected_nodes = expected_nodes[expected_nodes < V.dofmap.index_map.size_local]
    expected = np.sort((expected_nodes[:, None] * bs + np.arange(bs)).ravel())
    stars = [indices[offsets[p]:offsets[p + 1]] for p in range(len(offsets) - 1)]
    vertex_node = node_of(0, np.array([v], dtype=np.int32))[0]
    mine = [s for s in stars if vertex_node * bs in s]
    assert len(mine) == 1 and np.array_equal(mine[0], expected)
    assert all(edge_vertices.links(e).size == 2 for e in edges)


@pytest.mark.parametrize("dim", [2, 3])
def test_the_star_sweep_smooths_an_elasticity_matrix(dim):
    """As a stationary iteration x ← x + S(b − A x) on a clamped P2 elasticity matrix, the sweep
    smooths: from a random (rough) error, the error's energy falls at every sweep and by more
    than 20× in ten (serially and, with the split between processes, on 2 ranks)."""
    V = _p2_space(dim)
    msh = V.mesh
    u, v = ufl.TrialFunction(V), ufl.TestFunction(V)
    eps = lambda w: ufl.sym(ufl.grad(w))  # noqa: E731
    a = fem.form((2.0 * ufl.inner(eps(u), eps(v)) + ufl.div(u) * ufl.div(v)) * ufl.dx)
    clamped = dmesh.locate_entities_boundary(msh, dim - 1, lambda x: np.isclose(x[0], 0.0))
    bc = fem.dirichletbc(np.zeros(dim), fem.locate_dofs_topological(V, dim - 1, clamped), V)
    A = fem_petsc.assemble_matrix(a, bcs=[bc])
    A.assemble()
    smoother = star_smoother.StarSmoother(star_smoother.vertex_stars(V),
                                          A.getLocalSize()[0])
    smoother.set_operator(A)
    assert smoother.singular == 0
    b, x = A.createVecs()
    exact = b.duplicate()
    exact.setRandom()  # a rough error, which the sweeps must damp
    fem_petsc.set_bc(exact, [bc], scale=0.0)
    A.mult(exact, b)
    x.set(0.0)
    r, dx, e, Ae = (b.duplicate() for _ in range(4))
    energies = []
    for k in range(10):
        A.mult(x, r)
        r.aypx(-1.0, b)
        smoother.solve(r, dx)
        x.axpy(1.0, dx)
        x.copy(e)
        e.axpy(-1.0, exact)
        A.mult(e, Ae)
        energies.append(e.dot(Ae))
    energies = [exact.dot(b)] + energies  # (x = 0 at the start: the error is -exact)
    rates = np.array(energies[1:]) / np.array(energies[:-1])
    assert np.all(rates < 1.0), rates  # the error's energy falls at every sweep
    assert energies[-1] < 0.05 * energies[0], energies


def test_a_bad_star_sweep_option_is_refused():
    from vpcontact.paper import signorini as paper

    with pytest.raises(SolverOptionError, match="pmg_smooth_stars must be auto, true or false, "
                       "got 'jacobi'") as err:
        paper.signorini_3d(6, 2, 2, petsc_options={"lagged_fieldsplit_u_pmg_smooth_stars":
                                                   "jacobi"},
                           sigma_y=paper.SIGMA_Y, mu_star=paper.MU_STAR, formulation="mixed",
                           degree=2, linear="iterative")
    assert err.value.option == "lagged_fieldsplit_u_pmg_smooth_stars"


@pytest.mark.parametrize("above, stars", [(0, True), (1, False)])
def test_the_stars_smooth_large_blocks_by_default(above, stars, monkeypatch):
    """``pmg_smooth_stars auto`` (the default) smooths over the stars from STARS_FROM rows of the
    displacement block on (here the threshold moved to the size of the paper's 3-D test on
    6×2×2 cells, and one row above it), with Chebyshev–Jacobi below."""
    from vpcontact.paper import signorini as paper
    from vpcontact.solver import StepControl, advance
    from vpcontact.solver.pc import p_multigrid

    problem = paper.signorini_3d(6, 2, 2, petsc_options={}, sigma_y=paper.SIGMA_Y,
                                 mu_star=paper.MU_STAR, formulation="mixed", degree=2,
                                 linear="iterative")
    rows = problem.solver._block.is_u.getSize()
    monkeypatch.setattr(p_multigrid, "STARS_FROM", rows + above)
    list(advance(problem, 0.04, StepControl(0.02)))
    block = problem.solver.lagged_lu.inner.getPC().getFieldSplitSubKSP()[0]
    cycle = block.getPC().getPythonContext()
    assert (cycle.star_sweep is not None) == stars
    if stars:
        assert cycle.star_sweep.singular == 0


@pytest.mark.serial
def test_the_patches_schur_complements_equal_dense_ones():
    """schur_sum gives Σ_p B_p A_pp⁻¹ B_pᵀ (B_pᵀ the rows of Bᵀ on patch p) as coordinates, with
    the columns Bᵀ names (global: here offset by 100)."""
    A = _matrix()
    offsets, indices = _patches()
    smoother = _cpp.PatchSmoother(offsets, indices, 30)
    smoother.factorize(*_csr(A))
    Bt = np.random.default_rng(2).standard_normal((30, 7))
    Bt[np.abs(Bt) < 0.8] = 0.0
    starts, columns, values = _csr(Bt)
    rows, cols, entries, patch_starts = smoother.schur_sum(starts, columns + 100, values)
    assert patch_starts[0] == 0 and patch_starts[-1] == len(entries) and len(patch_starts) == 4
    result = np.zeros((7, 7))
    np.add.at(result, (rows - 100, cols - 100), entries)
    expected = np.zeros((7, 7))
    for p in range(3):
        I = indices[offsets[p]:offsets[p + 1]]
        expected += Bt[I].T @ np.linalg.solve(A[np.ix_(I, I)], Bt[I])
    assert np.allclose(result, expected, rtol=0, atol=1e-12)
    with pytest.raises(ValueError, match="Bt: 29 rows, the patches have 30"):
        smoother.schur_sum(*_csr(Bt[:29]))


@pytest.mark.serial
def test_refactorizing_the_changed_patches_equals_a_full_refactorization():
    """After rows and columns of A are replaced by the identity (SNES VI's active set moving),
    refactorizing only the patches that hold them gives the sweep and Schur terms of a full
    refactorization, to the last bit; the other patches keep theirs."""
    A = _matrix()
    offsets, indices = _patches()
    Bt = np.random.default_rng(2).standard_normal((30, 7))
    Bt[np.abs(Bt) < 0.8] = 0.0
    changed = np.array([3, 4])  # in patch 0 only
    A2, Bt2 = A.copy(), Bt.copy()
    A2[changed, :] = A2[:, changed] = 0.0
    A2[changed, changed] = 1.0
    Bt2[changed] = 0.0
    partial = _cpp.PatchSmoother(offsets, indices, 30)
    partial.factorize(*_csr(A))
    full = _cpp.PatchSmoother(offsets, indices, 30)
    full.factorize(*_csr(A2))
    patches = np.array([0], dtype=np.int64)
    partial.factorize(*_csr(A2), patches=patches)
    b = np.random.default_rng(1).standard_normal(30)
    y, y_full = np.zeros(30), np.zeros(30)
    partial.apply(b, y, 0.5)
    full.apply(b, y_full, 0.5)
    assert np.array_equal(y, y_full)
    _, _, entries, starts = full.schur_sum(*_csr(Bt2))
    _, _, some, some_starts = partial.schur_sum(*_csr(Bt2), patches=patches)
    assert np.array_equal(some, entries[starts[0]:starts[1]]) and list(some_starts) == [0, starts[1]]
    with pytest.raises(ValueError, match="patches: 3 is not a patch"):
        partial.factorize(*_csr(A2), patches=np.array([3], dtype=np.int64))
    with pytest.raises(ValueError, match="factorize all of them first"):
        _cpp.PatchSmoother(offsets, indices, 30).factorize(*_csr(A2), patches=patches)


def _stars_run(stars: str):
    return flowing_beam.run(options={"lagged_fieldsplit_u_pmg_smooth_stars": stars,
                                     "fieldsplit_u_pmg_smooth_stars": stars})


def test_with_the_stars_the_schur_block_is_theirs_and_the_answers_stay():
    """With the vertex stars the field split's Schur block is the stars' Schur complement
    C − ½ Σ_s B_s A_s⁻¹ B_sᵀ of SNES VI's full-size matrix (checked against scipy serially);
    the flowing beam's steps converge to the answers of the weighted mass's run (serially and on
    2 ranks)."""
    problem, steps = _stars_run("true")
    block = problem.solver._block
    assert block.star_schur is not None
    pc = problem.solver.lagged_lu.inner.getPC()
    assert pc.getFieldSplitSubKSP()[1].getOperators()[1].handle == block.star_schur.matrix.handle
    if COMM.size == 1:
        import scipy.sparse as sparse

        M = problem.solver.lagged_lu.matrix
        full = sparse.csr_matrix(M.getValuesCSR()[::-1], shape=M.getSize())
        iu, ip = block.is_u.getIndices(), block.is_p.getIndices()
        A, B = full[iu][:, iu].toarray(), full[ip][:, iu].toarray()
        expected = full[ip][:, ip].toarray()
        offsets, indices = block.coarse_space.stars
        for s in range(len(offsets) - 1):
            I = indices[offsets[s]:offsets[s + 1]]
            expected -= 0.5 * B[:, I] @ np.linalg.solve(A[np.ix_(I, I)], B[:, I].T)
        S = block.star_schur.matrix
        result = sparse.csr_matrix(S.getValuesCSR()[::-1], shape=S.getSize()).toarray()
        assert np.abs(result - expected).max() < 1e-10 * np.abs(expected).max()
    reference, reference_steps = _stars_run("false")
    assert reference.solver._block.star_schur is None
    u, u_ref = problem.u.x.array, reference.u.x.array
    assert np.abs(u - u_ref).max() < 1e-6 * np.abs(u_ref).max()
    assert [s.time for s in steps] == [s.time for s in reference_steps]
