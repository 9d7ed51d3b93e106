"""An explicit host loop in Python calling abut once per increment on numpy arrays.

The model and loop of examples/host_loop.rs (the Rust reference): a sheet of 8 x 8 point
masses joined by springs, thrown onto a fixed plate of 4 x 4 quads; penalty contact with
Coulomb friction 0.3 and half of critical damping; 600 increments of 1e-4. The host sums its
own forces (springs, then gravity) with numpy, abut adds the contact forces into the same
array (add=True), and the host takes a central-difference step. x and v are handed to abut in
place (C-contiguous float64), no copy.

    pip install ./python
    python examples/python/host_loop.py [cpu|vulkan|gl|auto] [forces.bin]
"""

import sys

import numpy as np

import abut

PLATE, SHEET, STEPS = 4, 8, 600
H, KS, G, DT = 0.1, 200.0, 9.81, 1e-4


def main() -> None:
    which = sys.argv[1] if len(sys.argv) > 1 else "cpu"
    out = open(sys.argv[2], "wb") if len(sys.argv) > 2 else None

    i, j = np.meshgrid(np.arange(PLATE + 1.0), np.arange(PLATE + 1.0))
    plate_x = np.stack([-1.0 + 0.5 * i.ravel(), -1.0 + 0.5 * j.ravel(), np.zeros(i.size)], 1)
    a = (np.arange(PLATE)[None, :] + (PLATE + 1) * np.arange(PLATE)[:, None]).ravel()
    quads = np.stack([a, a + 1, a + PLATE + 2, a + PLATE + 1], 1).astype(np.uint32)
    i, j = np.meshgrid(np.arange(SHEET + 0.0), np.arange(SHEET + 0.0))
    sheet_x = np.stack([H * i.ravel() - 0.35, H * j.ravel() - 0.35, np.full(i.size, 0.001)], 1)
    first = len(plate_x)
    x = np.ascontiguousarray(np.vstack([plate_x, sheet_x]))
    n = len(x)
    m = np.concatenate([np.ones(first), np.full(n - first, 0.01)])
    sheet = np.arange(first, n, dtype=np.uint32)
    grid = np.arange(first, n).reshape(SHEET, SHEET)
    si = np.concatenate([grid[:, :-1].ravel(), grid[:-1, :].ravel()])
    sj = np.concatenate([grid[:, 1:].ravel(), grid[1:, :].ravel()])

    device = {
        "cpu": abut.Device.cpu,
        "vulkan": lambda: abut.Device.gpu("vulkan"),
        "gl": lambda: abut.Device.gpu("gl"),
    }.get(which, abut.Device.auto)()
    model = abut.Model(3)
    model.add_nodes(x, m)
    plate = model.add_surface(quads)
    slaves = model.add_node_set(sheet)
    model.add_pair(slaves, plate, mu=0.3, damping=0.5)
    contact = abut.Contact(device, model)

    v = np.zeros((n, 3))
    v[first:] = [1.0, 0.25, -0.2]
    f = np.zeros((n, 3))
    touching, most = 0, 0
    for _ in range(STEPS):
        f[:] = 0.0
        d = x[sj] - x[si]
        length = np.sqrt(d[:, 0] * d[:, 0] + d[:, 1] * d[:, 1] + d[:, 2] * d[:, 2])
        fs = (KS * (length - H) / length)[:, None] * d
        np.add.at(f, si, fs)  # each spring's + onto i, in order
        np.subtract.at(f, sj, fs)  # then each − onto j
        f[first:, 2] -= m[first:] * G
        contact.penalty_step(x, v, DT, out=f, add=True)
        report = contact.report
        touching += report.active > 0
        most = max(most, report.active)
        if out:
            out.write(f.tobytes())
        v[first:] += DT * f[first:] / m[first:, None]
        x[first:] += DT * v[first:]
    if out:
        out.close()
    c = x[first:].mean(axis=0)
    print(
        f"python on {device}: {STEPS} increments, in contact in {touching}, at most {most} "
        f"nodes; sheet centre ({c[0]:.6f}, {c[1]:.6f}, {c[2]:.6f})"
    )


if __name__ == "__main__":
    main()
