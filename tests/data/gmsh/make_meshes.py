"""Writes the Gmsh test meshes of tests/io.rs with Gmsh itself (the gmsh Python package).

    pip install gmsh==4.15.2 && python3 tests/data/gmsh/make_meshes.py

Files (MSH 4.1):
  box_tets.msh         a 1 x 1 x 0.5 box of tetrahedra, ASCII; physical volume "block",
                       physical surfaces "top" (z = 0.5) and "bottom" (z = 0)
  box_tets_binary.msh  the same mesh, binary
  plate_quads.msh      a 2 x 2 plate of quadrilaterals at z = 0.5 (a master surface), ASCII;
                       physical surface "plate"
  rect_2d.msh          a 1 x 0.5 rectangle of triangles in the x-y plane, ASCII; physical surface
                       "body", physical curves "top" (y = 0.5) and "bottom" (y = 0)
"""
import os
import gmsh

here = os.path.dirname(os.path.abspath(__file__))


def box(binary):
    gmsh.initialize()
    gmsh.option.setNumber("General.Terminal", 0)
    gmsh.model.add("box")
    v = gmsh.model.occ.addBox(0, 0, 0, 1, 1, 0.5)
    gmsh.model.occ.synchronize()
    top, bottom = [], []
    for dim, tag in gmsh.model.getBoundary([(3, v)], oriented=False):
        x, y, z = gmsh.model.occ.getCenterOfMass(dim, tag)
        if abs(z - 0.5) < 1e-9:
            top.append(tag)
        elif abs(z) < 1e-9:
            bottom.append(tag)
    gmsh.model.addPhysicalGroup(3, [v], 1, "block")
    gmsh.model.addPhysicalGroup(2, top, 2, "top")
    gmsh.model.addPhysicalGroup(2, bottom, 3, "bottom")
    gmsh.option.setNumber("Mesh.MeshSizeMax", 0.3)
    gmsh.model.mesh.generate(3)
    gmsh.option.setNumber("Mesh.MshFileVersion", 4.1)
    gmsh.option.setNumber("Mesh.Binary", 1 if binary else 0)
    gmsh.write(os.path.join(here, "box_tets_binary.msh" if binary else "box_tets.msh"))
    gmsh.finalize()


def plate():
    gmsh.initialize()
    gmsh.option.setNumber("General.Terminal", 0)
    gmsh.model.add("plate")
    s = gmsh.model.occ.addRectangle(-0.5, -0.5, 0.5, 2, 2)
    gmsh.model.occ.synchronize()
    gmsh.model.addPhysicalGroup(2, [s], 1, "plate")
    gmsh.option.setNumber("Mesh.MeshSizeMax", 0.25)
    gmsh.option.setNumber("Mesh.RecombineAll", 1)
    gmsh.model.mesh.generate(2)
    gmsh.option.setNumber("Mesh.MshFileVersion", 4.1)
    gmsh.option.setNumber("Mesh.Binary", 0)
    gmsh.write(os.path.join(here, "plate_quads.msh"))
    gmsh.finalize()


def rect():
    gmsh.initialize()
    gmsh.option.setNumber("General.Terminal", 0)
    gmsh.model.add("rect")
    s = gmsh.model.occ.addRectangle(0, 0, 0, 1, 0.5)
    gmsh.model.occ.synchronize()
    top, bottom = [], []
    for dim, tag in gmsh.model.getBoundary([(2, s)], oriented=False):
        x, y, z = gmsh.model.occ.getCenterOfMass(dim, tag)
        if abs(y - 0.5) < 1e-9:
            top.append(tag)
        elif abs(y) < 1e-9:
            bottom.append(tag)
    gmsh.model.addPhysicalGroup(2, [s], 1, "body")
    gmsh.model.addPhysicalGroup(1, top, 2, "top")
    gmsh.model.addPhysicalGroup(1, bottom, 3, "bottom")
    gmsh.option.setNumber("Mesh.MeshSizeMax", 0.2)
    gmsh.model.mesh.generate(2)
    gmsh.option.setNumber("Mesh.MshFileVersion", 4.1)
    gmsh.option.setNumber("Mesh.Binary", 0)
    gmsh.write(os.path.join(here, "rect_2d.msh"))
    gmsh.finalize()


box(False)
box(True)
plate()
rect()
