"""The abut Python package: the example's forces equal the Rust API's bit for bit (CPU path
and lavapipe), a restart from saved state continues bit for bit, every kind of bad input
raises a named exception, outputs and kinematic corrections come back as numpy arrays, and
run_scene returns a run's history and summary.

Run from the repository: `pytest python/tests` (after `pip install ./python`). The Rust
reference is examples/host_loop.rs, run through cargo. With ABUT_REQUIRE_ADAPTER=1 a missing
Vulkan adapter fails the GPU cases instead of skipping them.
"""

import os
import subprocess
import sys
from pathlib import Path

import numpy as np
import pytest

import abut

ROOT = Path(__file__).resolve().parents[2]
REQUIRE = os.environ.get("ABUT_REQUIRE_ADAPTER") == "1"


def devices():
    """The CPU path and, when there is one, the Vulkan adapter."""
    yield "cpu"
    yield "vulkan"


def make_device(which):
    if which == "cpu":
        return abut.Device.cpu()
    try:
        return abut.Device.gpu(which)
    except abut.DeviceError:
        if REQUIRE:
            raise
        pytest.skip(f"no {which} adapter")


@pytest.mark.parametrize("which", list(devices()))
def test_the_example_writes_the_rust_apis_forces_bit_for_bit(which, tmp_path):
    make_device(which)
    rust, py = tmp_path / "rust.bin", tmp_path / "python.bin"
    subprocess.run(
        ["cargo", "run", "--quiet", "--release", "--example", "host_loop", "--", which, str(rust)],
        cwd=ROOT,
        check=True,
    )
    subprocess.run(
        [sys.executable, str(ROOT / "examples/python/host_loop.py"), which, str(py)],
        check=True,
    )
    a, b = rust.read_bytes(), py.read_bytes()
    assert len(a) == 600 * 89 * 3 * 8
    assert a == b, "the Python host loop's forces differ from the Rust API's"


def sheet(n=6, h=0.12):
    """A sheet of n x n slave nodes just above a 3 x 3 plate of quads (the master)."""
    p = 3
    i, j = np.meshgrid(np.arange(p + 1.0), np.arange(p + 1.0))
    plate = np.stack([-1 + 2 * i.ravel() / p, -1 + 2 * j.ravel() / p, 0 * i.ravel()], 1)
    a = (np.arange(p)[None, :] + (p + 1) * np.arange(p)[:, None]).ravel()
    quads = np.stack([a, a + 1, a + p + 2, a + p + 1], 1).astype(np.uint32)
    i, j = np.meshgrid(np.arange(n + 0.0), np.arange(n + 0.0))
    c = (n - 1) * h / 2
    top = np.stack([h * i.ravel() - c + 0.013, h * j.ravel() - c - 0.007, np.full(n * n, 2e-4)], 1)
    x = np.ascontiguousarray(np.vstack([plate, top]))
    m = np.concatenate([np.ones(len(plate)), np.full(n * n, 0.01)])
    return x, m, quads, np.arange(len(plate), len(x), dtype=np.uint32)


def sheet_model(mu=0.4):
    x, m, quads, slaves = sheet()
    model = abut.Model(3)
    model.add_nodes(x, m)
    plate = model.add_surface(quads)
    s = model.add_node_set(slaves)
    model.add_pair(s, plate, mu=mu)
    return model, x, m, slaves


def run(contact, x, v, m, slaves, steps, dt=2e-4):
    forces = []
    for _ in range(steps):
        f = contact.penalty_step(x, v, dt)
        forces.append(f.copy())
        f[slaves, 2] -= 200.0 * m[slaves]
        v[slaves] += dt * f[slaves] / m[slaves, None]
        x[slaves] += dt * v[slaves]
    return np.array(forces)


@pytest.mark.parametrize("which", list(devices()))
def test_a_restart_from_saved_state_continues_bit_for_bit(which):
    device = make_device(which)
    model, x, m, slaves = sheet_model()
    v = np.zeros_like(x)
    v[slaves] = [0.8, -0.3, -0.05]
    whole = abut.Contact(device, model)
    run(whole, x, v, m, slaves, 87)
    state = whole.save_state()
    x2, v2 = x.copy(), v.copy()
    rest = run(whole, x, v, m, slaves, 60)
    restarted = abut.Contact(device, model)
    restarted.restore_state(state)
    again = run(restarted, x2, v2, m, slaves, 60)
    assert np.any(rest != 0)
    assert rest.tobytes() == again.tobytes()


def test_outputs_come_back_as_arrays():
    model, x, m, slaves = sheet_model()
    contact = abut.Contact(abut.Device.cpu(), model)
    contact.request_outputs(True)
    v = np.zeros_like(x)
    v[slaves] = [0.5, 0.0, -0.05]
    for _ in range(100):
        run(contact, x, v, m, slaves, 1)
        if contact.report.active > 0:
            break
    out = contact.output(0)
    n = len(slaves)
    assert out["slaves"].tolist() == slaves.tolist()
    assert out["cpress"].shape == (n,) and out["normal"].shape == (n, 3)
    assert set(out["cstatus"].tolist()) <= {-1, 0, 1, 2}
    assert out["cfn"].shape == (3,) and out["cfn"][2] > 0
    assert contact.report.active > 0 and contact.report.warnings == []


def test_kinematic_contact_corrects_the_hosts_arrays_in_place():
    model = abut.Model(3)
    x = np.array([[0.0, 0.0, -0.01], [0.5, 0.0, 0.2]])
    model.add_nodes(x, np.array([1.0, 1.0]))
    nodes = model.add_node_set(np.array([0, 1], dtype=np.uint32))
    body = model.add_rigid_body(1e3, np.eye(3).tolist(), ("plane", [0, 0, 0], [0, 0, 1]))
    model.add_rigid_pair(nodes, body)
    contact = abut.Contact(abut.Device.cpu(), model)
    v = np.array([[0.0, 0.0, -100.0], [0.0, 0.0, 0.0]])
    bodies = np.zeros((1, 18))
    bodies[0, 3:12] = np.eye(3).ravel()
    report = contact.kinematic_step(x, v, 1e-4, bodies)
    assert report.active == 1
    # the node and the plate share the correction by their masses: on the plate after it
    assert bodies[0, 2] < 0 and abs(x[0, 2] - bodies[0, 2]) < 1e-12 and x[1, 2] == 0.2
    assert v[0, 2] > -100.0


def test_every_bad_input_raises_a_named_exception():
    with pytest.raises(abut.BadValueError, match="dim = 4"):
        abut.Model(4)
    model, x, m, slaves = sheet_model()
    bad = x.copy()
    bad[5, 1] = np.nan
    with pytest.raises(abut.BadValueError, match="node 5: coordinate 1"):
        abut.Model(3).add_nodes(bad, m)
    with pytest.raises(abut.BadValueError, match="mass"):
        abut.Model(3).add_nodes(x, -m)
    with pytest.raises(abut.LengthError, match=r"expected \(n, 3\)"):
        abut.Model(3).add_nodes(x[:, :2], m)
    with pytest.raises(abut.OutOfRangeError, match="999"):
        model.add_surface(np.array([[0, 1, 999, 2]], dtype=np.uint32))
    with pytest.raises(abut.GeometryError, match="more than once"):
        model.add_surface(np.array([[0, 1, 1, 2]], dtype=np.uint32))
    with pytest.raises(abut.OutOfRangeError):
        model.add_pair(9, 0)
    with pytest.raises(abut.BadValueError, match="enforcement"):
        model.add_pair(0, 0, enforcement="glue")
    with pytest.raises(abut.BadValueError, match="sliding"):
        model.add_pair(0, 0, sliding="sideways")
    with pytest.raises(abut.BadValueError, match="law"):
        model.add_pair(0, 0, law=("cubic", 1.0))
    with pytest.raises(abut.BadValueError):
        model.add_pair(0, 0, law=("exponential", -1.0, 1.0))
    with pytest.raises(abut.BadValueError, match="surface"):
        model.add_rigid_body(1.0, np.eye(3).tolist(), ("torus", [0, 0, 0], 1.0))
    with pytest.raises(abut.BadValueError, match="backend"):
        abut.Device.gpu("opencl")
    with pytest.raises(abut.DeviceError, match="no adapter has this name"):
        abut.Device.gpu("any", "no adapter has this name")

    contact = abut.Contact(abut.Device.cpu(), model)
    v = np.zeros_like(x)
    with pytest.raises(abut.LengthError, match="positions"):
        contact.penalty_step(x[:-1], v[:-1], 1e-4)
    with pytest.raises(abut.LengthError, match=r"expected \(n, 3\)"):
        contact.penalty_step(x[:, :2].copy(), v, 1e-4)
    with pytest.raises(abut.BadValueError, match="C-contiguous"):
        contact.penalty_step(np.asfortranarray(x), v, 1e-4)
    with pytest.raises(abut.BadValueError, match="dt"):
        contact.penalty_step(x, v, 0.0)
    vn = v.copy()
    vn[3, 2] = np.inf
    with pytest.raises(abut.BadValueError):
        contact.penalty_step(x, vn, 1e-4)
    with pytest.raises(TypeError):
        contact.penalty_step(x.astype(np.float32), v, 1e-4)
    contact.penalty_step(x, v, 1e-4)
    with pytest.raises(abut.OutOfRangeError, match="pass 1"):
        contact.output(0, 1)
    with pytest.raises(abut.BadValueError, match="saved contact state"):
        contact.restore_state(b"not a state")
    with pytest.raises(abut.LengthError, match="rows"):
        contact.penalty_step(x, v, 1e-4, out=np.zeros((3, 3)))
    other, *_ = sheet_model()
    small = abut.Model(3)
    xs, ms, quads, slaves_s = sheet()
    small.add_nodes(xs[:25], ms[:25])
    s = small.add_surface(quads)
    small.add_pair(small.add_node_set(slaves_s[:9]), s)
    with pytest.raises(abut.LengthError, match="slaves of a penalty pass"):
        abut.Contact(abut.Device.cpu(), small).restore_state(contact.save_state())
    assert issubclass(abut.LengthError, abut.AbutError)


def test_the_combined_increment_takes_both_limits():
    both = abut.combined_increment(1e-5, 3e-5)
    assert both < 1e-5 and both == abut.combined_increment(1e-5, 3e-5, 0.9, 0.5)
    assert abut.combined_increment(1e-5, float("inf")) == 1e-5


def test_run_scene_returns_history_and_summary(tmp_path):
    history, summary = abut.run_scene(ROOT / "scenes/incline.toml", abut.Device.cpu(), tmp_path)
    assert history["time"].dtype == np.float64 and len(history["time"]) > 10
    assert np.all(np.diff(history["time"]) > 0)
    assert "contact_force" in history and summary["increments"] > 0
    assert summary["title"] and (tmp_path / "summary.json").exists()
    with pytest.raises(abut.IoError, match="nowhere.toml"):
        abut.run_scene(tmp_path / "nowhere.toml", abut.Device.cpu())
