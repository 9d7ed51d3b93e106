"""abut: GPU node-to-surface contact for explicit dynamics (Abaqus/Explicit contact-pair
semantics), called once per increment from a Python host loop on numpy arrays.

    import numpy as np, abut
    model = abut.Model(3)
    model.add_nodes(coords, masses)              # (n, 3), (n,) float64
    plate = model.add_surface(quads)             # (k, 4) uint32 node ids
    sheet = model.add_node_set(slave_ids)        # (m,) uint32
    model.add_pair(sheet, plate, mu=0.3)         # penalty, Coulomb friction
    contact = abut.Contact(abut.Device.auto(), model)
    for step in range(steps):
        f = contact.penalty_step(x, v, dt)       # x, v read in place: (n, 3) float64
        ...                                      # the host's own central differences

Positions, velocities and forces are (n, 3) float64 arrays; C-contiguous ones are read in
place, others are refused (abut does not copy them silently). Errors raise subclasses of
AbutError carrying the library's message, which names the item at fault.
"""

from __future__ import annotations

import csv
import json
import os
import tempfile
from typing import Any, Dict, Optional, Tuple

import numpy as np

from ._abut import (  # noqa: F401  (the extension module's names are the package's)
    AbutError,
    BadValueError,
    Contact,
    ContactError,
    Device,
    DeviceError,
    GeometryError,
    IoError,
    LengthError,
    Model,
    OutOfRangeError,
    Report,
    __version__,
    combined_increment,
    run_scene_json,
)

__all__ = [
    "AbutError",
    "BadValueError",
    "Contact",
    "ContactError",
    "Device",
    "DeviceError",
    "GeometryError",
    "IoError",
    "LengthError",
    "Model",
    "OutOfRangeError",
    "Report",
    "combined_increment",
    "run_scene",
]


def run_scene(
    path: str | os.PathLike[str],
    device: Optional[Device] = None,
    output: Optional[str | os.PathLike[str]] = None,
) -> Tuple[Dict[str, np.ndarray], Dict[str, Any]]:
    """Runs the scene file at `path` (abut's TOML scenes) on `device` (None: Device.auto()).

    Returns (history, summary): history maps each column of the run's history.csv (time,
    energies, contact force, ...) to a float64 array; summary is the run's summary.json as a
    dict. With `output`, the run's files (history.csv, summary.json, vtk/) stay there;
    without, they go to a temporary directory that is removed.
    """
    def read(out: str) -> Tuple[Dict[str, np.ndarray], Dict[str, Any]]:
        summary = json.loads(run_scene_json(os.fspath(path), out, device))
        with open(os.path.join(out, "history.csv"), newline="") as f:
            rows = list(csv.reader(f))
        header, body = rows[0], rows[1:]
        history = {
            name: np.array([float(r[k]) for r in body], dtype=np.float64)
            for k, name in enumerate(header)
        }
        return history, summary

    if output is not None:
        return read(os.fspath(output))
    with tempfile.TemporaryDirectory(prefix="abut-") as out:
        return read(out)
