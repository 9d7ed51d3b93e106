"""Type stubs for abut (the extension module abut._abut and the package around it)."""

import os
from typing import Any, Dict, List, Optional, Sequence, Tuple, Union

import numpy as np
import numpy.typing as npt

__version__: str

Law = Union[
    None,
    Tuple[str, float, float],  # ("exponential", clearance, pressure)
    Tuple[str, Sequence[Tuple[float, float]]],  # ("tabular", [(overclosure, pressure), ...])
    Tuple[str, float],  # ("slope", pressure per overclosure)
]

class AbutError(Exception):
    """An error of the abut library; its message names the item at fault."""

class LengthError(AbutError):
    """An array's length or shape does not match what it describes."""

class OutOfRangeError(AbutError):
    """An id or index names nothing."""

class BadValueError(AbutError):
    """A value is not allowed: NaN or infinite, non-positive, an unknown option name."""

class GeometryError(AbutError):
    """A surface's facets cannot be used."""

class DeviceError(AbutError):
    """No adapter, or the GPU failed."""

class ContactError(AbutError):
    """The contact failed during an increment."""

class IoError(AbutError):
    """A file could not be read or parsed."""

class Device:
    """A GPU adapter or the CPU path."""

    @staticmethod
    def auto() -> Device:
        """The best GPU adapter, else the CPU path."""
    @staticmethod
    def cpu() -> Device:
        """The CPU path (the kernels' mirrors)."""
    @staticmethod
    def gpu(backend: str = "any", name: Optional[str] = None) -> Device:
        """A GPU adapter of `backend` ("any", "vulkan", "gl", "metal", "dx12") whose name
        contains `name`."""
    @property
    def is_gpu(self) -> bool: ...

class Model:
    """Nodes with masses, surfaces, node sets, pairs, rigid bodies and parts."""

    def __init__(self, dim: int = 3) -> None: ...
    @property
    def node_count(self) -> int: ...
    def add_nodes(
        self, coords: npt.NDArray[np.float64], masses: npt.NDArray[np.float64]
    ) -> int:
        """Adds nodes at `coords` ((n, dim)) with `masses` ((n,)); returns the first id."""
    def add_surface(self, facets: npt.NDArray[np.uint32]) -> int:
        """Adds a master surface of (k, 2) segments, (k, 3) triangles or (k, 4) quads."""
    def add_node_set(
        self,
        nodes: npt.NDArray[np.uint32],
        areas: Optional[npt.NDArray[np.float64]] = None,
    ) -> int:
        """Adds a node set (slave nodes), optionally with tributary areas."""
    def add_pair(
        self,
        slave: int,
        master: int,
        *,
        enforcement: str = "penalty",
        stiffness: str = "auto",
        stiffness_value: float = 0.0,
        stiffness_scale: float = 1.0,
        law: Law = None,
        damping: float = 0.03,
        mu: Optional[float] = None,
        mu_kinetic: Optional[float] = None,
        decay: float = 0.0,
        stick_stiffness: float = 1.0,
        sliding: str = "finite",
        search_radius: Optional[float] = None,
        schedule: Optional[Tuple[int, float, bool]] = None,
        balanced: Optional[Tuple[int, float]] = None,
        pass_weight: float = 1.0,
    ) -> int:
        """Adds a contact pair: node set `slave` against surface `master`.

        enforcement "penalty" or "kinematic"; stiffness "auto" (scale), "modulus" (value =
        E, scale), "absolute" or "per_area" (value); law None (penalty: linear; kinematic:
        hard) or a softened law; mu None (frictionless) or Coulomb friction; sliding
        "finite", "small" or "infinitesimal"; schedule (interval, budget, wide_local);
        balanced (slave surface, weight of the slave-on-master pass)."""
    def add_rigid_body(
        self, mass: float, inertia: Sequence[Sequence[float]], surface: Tuple[Any, ...]
    ) -> int:
        """Adds a rigid body with an analytical surface ("plane", point, normal), ("sphere",
        centre, radius), ("cylinder", point, axis, radius), ("line", ...), ("circle", ...)."""
    def add_rigid_pair(self, slave: int, body: int, softened: Law = None) -> int: ...
    def add_rigid_part(
        self, nodes: npt.NDArray[np.uint32], mass: float, inertia: Sequence[Sequence[float]]
    ) -> int: ...

class Report:
    """What an increment reported."""

    stable_dt: float
    approach_dt: float
    max_overclosure: float
    active: int
    slipping: int
    fast_nodes: int
    fastest: Optional[Tuple[int, int, float, float]]
    global_searches: int
    unanchored: int
    max_overclosure_after: float
    kinetic_energy_change: float
    warnings: List[str]

class Contact:
    """Search and enforcement of every pair of a model, once per increment."""

    def __init__(self, device: Device, model: Model) -> None: ...
    def request_outputs(self, yes: bool) -> None: ...
    def set_reference_increment(self, dt: float) -> None: ...
    def penalty_step(
        self,
        x: npt.NDArray[np.float64],
        v: npt.NDArray[np.float64],
        dt: float,
        out: Optional[npt.NDArray[np.float64]] = None,
        add: bool = False,
    ) -> npt.NDArray[np.float64]:
        """One penalty increment; returns the contact forces ((n, 3)), in `out` if given."""
    @property
    def report(self) -> Report: ...
    def kinematic_step(
        self,
        x: npt.NDArray[np.float64],
        v: npt.NDArray[np.float64],
        dt: float,
        bodies: Optional[npt.NDArray[np.float64]] = None,
    ) -> Report:
        """One kinematic increment; corrects x, v (and bodies, (k, 18)) in place."""
    @property
    def kinematic_report(self) -> Report: ...
    def adjust_initial_overclosure(
        self,
        x: npt.NDArray[np.float64],
        dt: float,
        bodies: Optional[npt.NDArray[np.float64]] = None,
    ) -> float: ...
    def output(self, pair: int, pass_: int = 0, rigid: bool = False) -> Dict[str, Any]:
        """CSTATUS, COPEN, CPRESS, CSHEAR1/2, normals, forces, CFN, CFS of one pass."""
    def save_state(self) -> bytes: ...
    def restore_state(self, state: bytes) -> None: ...

def combined_increment(
    element_dt: float, contact_dt: float, safety: float = 0.9, contact_safety: float = 0.5
) -> float:
    """The increment for nodes carrying elements and penalty springs together."""

def run_scene_json(path: str, output: str, device: Optional[Device] = None) -> str: ...
def run_scene(
    path: Union[str, "os.PathLike[str]"],
    device: Optional[Device] = None,
    output: Optional[Union[str, "os.PathLike[str]"]] = None,
) -> Tuple[Dict[str, np.ndarray], Dict[str, Any]]:
    """Runs a scene file; returns (history columns as arrays, summary dict)."""
