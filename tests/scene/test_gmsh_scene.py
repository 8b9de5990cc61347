# SPDX-License-Identifier: MIT
"""Scenes on Gmsh meshes: boundary parts by physical tag, and a located error for a missing tag."""

import re

import gmsh  # python3-gmsh; scripts/setup.sh installs it
import numpy as np
import pytest
from mpi4py import MPI

from vpcontact import cli
from vpcontact import scene as scenes
from vpcontact.scene import build
from tests.support.scenes import scene_text

LEFT, RIGHT, BOTTOM, BODY = 1, 2, 3, 10


def _rectangle_msh(path, order: int = 1, quads_too: bool = False):
    """A 2 × 1 rectangle meshed by Gmsh; physical lines 1 (x = 0), 2 (x = 2), 3 (y = 0);
    triangles of ``order`` (2: six-node, curved-capable geometry); with ``quads_too`` a second
    rectangle above it, meshed in quadrilaterals, in the body's group too."""
    if MPI.COMM_WORLD.rank == 0:
        gmsh.initialize(["gmsh", "-v", "0"])  # argv[0] is the program name
        gmsh.model.add("rectangle")
        surface = gmsh.model.occ.addRectangle(0.0, 0.0, 0.0, 2.0, 1.0)
        upper = gmsh.model.occ.addRectangle(0.0, 1.0, 0.0, 2.0, 1.0) if quads_too else None
        if quads_too:
            gmsh.model.occ.fragment([(2, surface)], [(2, upper)])
        gmsh.model.occ.synchronize()
        if quads_too:
            gmsh.model.mesh.setRecombine(2, upper)
        lines = {}
        for dim, tag in gmsh.model.getBoundary([(2, surface)], oriented=False):
            x, y, _ = gmsh.model.occ.getCenterOfMass(dim, tag)
            lines[(round(x, 6), round(y, 6))] = tag
        gmsh.model.addPhysicalGroup(1, [lines[(0.0, 0.5)]], LEFT)
        gmsh.model.addPhysicalGroup(1, [lines[(2.0, 0.5)]], RIGHT)
        gmsh.model.addPhysicalGroup(1, [lines[(1.0, 0.0)]], BOTTOM)
        gmsh.model.addPhysicalGroup(2, [surface] + ([upper] if quads_too else []), BODY)
        gmsh.option.setNumber("Mesh.CharacteristicLengthMax", 0.2)
        gmsh.model.mesh.generate(2)
        gmsh.model.mesh.setOrder(order)
        gmsh.write(str(path))
        gmsh.finalize()
    MPI.COMM_WORLD.barrier()


def _write(folder, floor_tag):
    path = folder / "block.toml"
    if MPI.COMM_WORLD.rank == 0:
        path.write_text(scene_text("gmsh_block", floor_tag=floor_tag))
    MPI.COMM_WORLD.barrier()
    return path


def test_gmsh_scene_runs_with_tagged_parts(shared_tmp_path):
    _rectangle_msh(shared_tmp_path / "block.msh")
    model = build(scenes.load(_write(shared_tmp_path, BOTTOM)))
    comm = MPI.COMM_WORLD
    floor = model.facet_tags.find(model.part_tags["floor"])
    length = comm.allreduce(len(floor), op=MPI.SUM)
    assert length >= 10, "the bottom line carries about 2 / 0.2 facets"
    for _ in range(4):
        model.problem.step(0.25)
    u = model.problem.u.x.array.reshape(-1, 2)
    low = comm.allreduce(float(u[:, 1].min()), op=MPI.MIN)
    assert low < 0.0 and np.isfinite(u).all()


@pytest.mark.parametrize("contact", ["normal_compliance", "signorini"])
def test_friction_on_a_second_order_gmsh_mesh(shared_tmp_path, contact):
    """Six-node triangles from Gmsh, Coulomb friction on the floor: the stick stiffness's facet
    size comes from the facet Jacobian on their (possibly curved) facets, as FFCx has no
    FacetArea there (the run stopped with an internal error); it equals the facet's length on
    these straight ones, so the floor's ∫ h_F ds is the sum of its facets' squared lengths."""
    from dolfinx import fem
    import ufl
    from vpcontact.model.nodal_areas import facet_size

    _rectangle_msh(shared_tmp_path / "block.msh", order=2)
    text = scene_text("gmsh_block", floor_tag=BOTTOM).replace("mu = 1e-7\n", (
        'mu = 1e-7\nfriction = { type = "coulomb", coefficient = 0.3 }\n'
        if contact == "normal_compliance" else
        'friction = { type = "coulomb", coefficient = 0.3 }\n'
        'obstacle = { shape = "plane", point = [0, 0], normal = [0, 1] }\n')).replace(
        'type = "normal_compliance"', f'type = "{contact}"')
    path = shared_tmp_path / "block.toml"
    if MPI.COMM_WORLD.rank == 0:
        path.write_text(text)
    MPI.COMM_WORLD.barrier()
    model = build(scenes.load(path))
    comm, msh = MPI.COMM_WORLD, model.problem.mesh
    assert msh.geometry.cmap.degree == 2
    floor = model.part_tags["floor"]
    ds = ufl.Measure("ds", domain=msh, subdomain_data=model.facet_tags)(floor)
    lengths = comm.allreduce(fem.assemble_scalar(fem.form(facet_size(msh) * ds)), op=MPI.SUM)
    count = comm.allreduce(len(model.facet_tags.find(floor)), op=MPI.SUM)
    assert lengths == pytest.approx(2.0 * 2.0 / count, rel=0.05)  # ≈ count facets of 2/count
    for _ in range(4):
        model.problem.step(0.25)
    assert np.isfinite(model.problem.u.x.array).all()


def test_missing_gmsh_tag_is_reported_at_its_part(shared_tmp_path, capsys):
    _rectangle_msh(shared_tmp_path / "block.msh")
    path = _write(shared_tmp_path, 7)
    out = shared_tmp_path / "out"
    assert cli.main(["run", str(path), "--out", str(out)]) == 2
    err = capsys.readouterr().err
    if MPI.COMM_WORLD.rank == 0:
        line = 1 + path.read_text().splitlines().index("[boundary.floor]")
        assert re.search(rf"{re.escape(str(path))}:{line}: boundary.floor: .*tag 7 marks no boundary facet", err), err
    assert not out.exists()


def test_a_mesh_of_triangles_and_quadrilaterals_is_a_located_error(shared_tmp_path, capsys):
    """dolfinx takes one cell type per mesh: a Gmsh file mixing triangles and quadrilaterals
    stopped with an internal error (an assertion inside dolfinx), and hung on 2 ranks. It is
    refused at mesh.file, on every rank, before any mesh is built."""
    _rectangle_msh(shared_tmp_path / "block.msh", quads_too=True)
    path = _write(shared_tmp_path, BOTTOM)
    assert cli.main(["validate", str(path)]) == 2
    if MPI.COMM_WORLD.rank == 0:
        err = capsys.readouterr().err
        assert f"{path}:4: mesh.file: the Gmsh mesh mixes cell types (Triangle 3, " \
            "Quadrilateral 4)" in err, err


def test_unreadable_gmsh_file_is_a_located_error(shared_tmp_path):
    if MPI.COMM_WORLD.rank == 0:
        (shared_tmp_path / "block.msh").write_text("this is not a mesh\n")
    MPI.COMM_WORLD.barrier()
    scene = scenes.load(_write(shared_tmp_path, BOTTOM))
    with pytest.raises(scenes.SceneError, match=r"block.toml:4: mesh.file: "):
        build(scene)


def test_mesh_dimension_that_does_not_match_the_file_is_a_located_error(shared_tmp_path, capsys):
    """A 2-D Gmsh mesh declared dim = 3 (and the reverse, which used to end in a UFL traceback)
    is refused at mesh.dim by validate and by run: exit 2, nothing written."""
    _rectangle_msh(shared_tmp_path / "block.msh")
    path = _write(shared_tmp_path, BOTTOM)
    if MPI.COMM_WORLD.rank == 0:
        path.write_text(path.read_text().replace("dim = 2", "dim = 3").replace(
            'traction = [0.0, "-1e3*t"]', 'traction = [0.0, "-1e3*t", 0.0]').replace(
            'plane = "stress"\n', ""))
    MPI.COMM_WORLD.barrier()
    out = shared_tmp_path / "out"
    for command in (["validate", str(path)], ["run", str(path), "--out", str(out)]):
        assert cli.main(command) == 2
        err = capsys.readouterr().err
        if MPI.COMM_WORLD.rank == 0:
            assert re.search(r"block.toml:5: mesh.dim: the Gmsh file holds a 2-D mesh but "
                             r"dim = 3: set dim = 2", err), err
    assert not out.exists()
    if MPI.COMM_WORLD.rank == 0:  # a 3-D mesh declared 2-D
        gmsh.initialize(["gmsh", "-v", "0"])
        gmsh.model.add("box")
        volume = gmsh.model.occ.addBox(0.0, 0.0, 0.0, 2.0, 1.0, 1.0)
        gmsh.model.occ.synchronize()
        gmsh.model.addPhysicalGroup(3, [volume], BODY)
        gmsh.model.addPhysicalGroup(2, [s for _, s in gmsh.model.getBoundary([(3, volume)])], 1)
        gmsh.option.setNumber("Mesh.CharacteristicLengthMax", 0.5)
        gmsh.model.mesh.generate(3)
        gmsh.write(str(shared_tmp_path / "block.msh"))
        gmsh.finalize()
        path.write_text(path.read_text().replace("dim = 3", "dim = 2").replace(
            'traction = [0.0, "-1e3*t", 0.0]', 'traction = [0.0, "-1e3*t"]'))
    MPI.COMM_WORLD.barrier()
    with pytest.raises(scenes.SceneError, match=r"mesh.dim: the Gmsh file holds a 3-D mesh but "
                                                r"dim = 2: set dim = 3"):
        build(scenes.load(path))
