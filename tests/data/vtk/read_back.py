"""Reads abut's VTK output back with an independent reader (meshio for the .vtu frames, the
standard library's XML parser for the .pvd collection) and prints what it found as JSON:

    python3 tests/data/vtk/read_back.py DIR NAME

tests/io.rs compares these figures with what abut wrote.
"""
import json
import os
import sys
import xml.etree.ElementTree as ET

import meshio

d, name = sys.argv[1], sys.argv[2]
tree = ET.parse(os.path.join(d, name + ".pvd"))
sets = tree.getroot().find("Collection").findall("DataSet")
out = {"times": [float(s.get("timestep")) for s in sets], "frames": []}
for s in sets:
    m = meshio.read(os.path.join(d, s.get("file")))
    cells = {c.type: len(c.data) for c in m.cells}
    pd = m.point_data
    facet_force = [0.0, 0.0, 0.0]
    for block in m.cell_data["FACET_FORCE"]:
        for row in block:
            for a in range(3):
                facet_force[a] += float(row[a])
    out["frames"].append(
        {
            "points": int(len(m.points)),
            "cells": cells,
            "cstatus_in_contact": int(sum(1 for v in pd["CSTATUS"] if v > 0)),
            "cstatus_slaves": int(sum(1 for v in pd["CSTATUS"] if v >= 0)),
            "cpress_sum": float(sum(pd["CPRESS"])),
            "copen_min": float(min(pd["COPEN"])),
            "cforce_sum": [float(sum(r[a] for r in pd["CFORCE"])) for a in range(3)],
            "facet_force_sum": facet_force,
            "z_sum": float(sum(p[2] for p in m.points)),
        }
    )
print(json.dumps(out))
