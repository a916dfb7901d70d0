"""Write the 3-D Gmsh example meshes ``pad_tet.msh`` and ``pad_hex.msh`` (run once; needs the
``gmsh`` Python package from PyPI, which the shakedown package itself does not use).

A pad ``[0, 1] x [0, 1] x [0, 0.5]`` [length] with physical groups naming its surfaces:
``contact`` (the bottom, z = 0, on the obstacle), ``clamped`` (the top, z = 0.5, held),
``loaded`` (the side x = 1, loaded), and the volume ``pad``.  ``pad_tet.msh``: linear tetrahedra
(mesh size 0.25); ``pad_hex.msh``: 4 x 4 x 2 trilinear hexahedra (transfinite, recombined).
Both in the MSH 4.1 ASCII format, read by :func:`shakedown.fe.from_file` through meshio.

    python3 data/models/make_pad_mesh.py
"""

from pathlib import Path

import gmsh

HERE = Path(__file__).resolve().parent


def pad(path: Path, hexahedra: bool) -> None:
    gmsh.initialize()
    gmsh.option.setNumber("General.Terminal", 0)
    gmsh.model.add("pad")
    vol = gmsh.model.occ.addBox(0.0, 0.0, 0.0, 1.0, 1.0, 0.5)
    gmsh.model.occ.synchronize()
    faces = {}
    for dim, tag in gmsh.model.getBoundary([(3, vol)], oriented=False):
        x, y, z = gmsh.model.occ.getCenterOfMass(dim, tag)
        faces[(round(x, 6), round(y, 6), round(z, 6))] = tag
    by_name = {"contact": faces[(0.5, 0.5, 0.0)], "clamped": faces[(0.5, 0.5, 0.5)],
               "loaded": faces[(1.0, 0.5, 0.25)]}
    for name, tag in by_name.items():
        gmsh.model.addPhysicalGroup(2, [tag], name=name)
    gmsh.model.addPhysicalGroup(3, [vol], name="pad")
    if hexahedra:
        for c in gmsh.model.getEntities(1):
            lo = gmsh.model.getBoundingBox(*c)
            length = max(lo[3] - lo[0], lo[4] - lo[1], lo[5] - lo[2])
            gmsh.model.mesh.setTransfiniteCurve(c[1], 3 if length < 0.75 else 5)
        for s in gmsh.model.getEntities(2):
            gmsh.model.mesh.setTransfiniteSurface(s[1])
            gmsh.model.mesh.setRecombine(2, s[1])
        gmsh.model.mesh.setTransfiniteVolume(vol)
    else:
        gmsh.option.setNumber("Mesh.MeshSizeMax", 0.25)
    gmsh.model.mesh.generate(3)
    gmsh.option.setNumber("Mesh.MshFileVersion", 4.1)
    gmsh.write(str(path))
    gmsh.finalize()


if __name__ == "__main__":
    pad(HERE / "pad_tet.msh", hexahedra=False)
    pad(HERE / "pad_hex.msh", hexahedra=True)
