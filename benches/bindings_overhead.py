"""The cost of one penalty increment called from Rust, from C (libabut) and from Python (the
abut package): the model of examples/overhead.rs in each, at 10^3, 10^5 and 10^6 slaves, on the
CPU path and lavapipe. Rounds alternate the three so that the machine's drift falls on all of
them; each cell is the median over rounds of the mean steady-state increment (the first call,
which builds pipelines and buffers, apart), and the ratios are also given for the fastest round
of each (the least disturbed by the machine). Writes a markdown table to stdout.

    cargo build --release --example overhead -p abut-capi
    cc -std=c11 -O2 -Iinclude examples/c/overhead.c -Ltarget/release -labut -lm -o target/overhead_c
    pip install ./python
    python3 benches/bindings_overhead.py [--rounds 5] [--sizes 1000,100000,1000000] [--devices cpu,vulkan]
"""

import argparse
import os
import platform
import statistics
import subprocess
import time
from pathlib import Path

import numpy as np

import abut

ROOT = Path(__file__).resolve().parents[1]


def python_case(device: str, want: int, reps: int):
    side = int(round(want ** 0.5))
    plate = side // 2 + 1
    i, j = np.meshgrid(np.arange(plate + 1.0), np.arange(plate + 1.0))
    px = np.stack([2.0 * i.ravel() - 1.0, 2.0 * j.ravel() - 1.0, np.zeros(i.size)], 1)
    a = (np.arange(plate)[None, :] + (plate + 1) * np.arange(plate)[:, None]).ravel()
    quads = np.stack([a, a + 1, a + plate + 2, a + plate + 1], 1).astype(np.uint32)
    i, j = np.meshgrid(np.arange(side + 0.0), np.arange(side + 0.0))
    sx = np.stack([i.ravel(), j.ravel(), np.full(i.size, -0.01)], 1)
    x = np.ascontiguousarray(np.vstack([px, sx]))
    n = len(x)
    model = abut.Model(3)
    model.add_nodes(x, np.ones(n))
    surface = model.add_surface(quads)
    s = model.add_node_set(np.arange(len(px), n, dtype=np.uint32))
    model.add_pair(s, surface, mu=0.3)
    dev = abut.Device.cpu() if device == "cpu" else abut.Device.gpu(device)
    contact = abut.Contact(dev, model)
    v = np.zeros((n, 3))
    f = np.zeros((n, 3))
    times = []
    for _ in range(reps + 1):
        t = time.perf_counter()
        contact.penalty_step(x, v, 1e-3, out=f)
        times.append(time.perf_counter() - t)
    assert np.any(f[:, 2] != 0.0)
    return side * side, times[0], sum(times[1:]) / reps


def native(cmd, device, want, reps):
    env = dict(os.environ, LD_LIBRARY_PATH=str(ROOT / "target/release"))
    out = subprocess.run(
        [*cmd, device, str(want), str(reps)], env=env, check=True, capture_output=True, text=True
    ).stdout.split()
    return int(out[1]), float(out[2]), float(out[3])


def main():
    p = argparse.ArgumentParser()
    p.add_argument("--rounds", type=int, default=5)
    p.add_argument("--sizes", default="1000,100000,1000000")
    p.add_argument("--devices", default="cpu,vulkan")
    args = p.parse_args()
    rust = [str(ROOT / "target/release/examples/overhead")]
    c = [str(ROOT / "target/overhead_c")]
    print(f"machine: {platform.processor() or platform.machine()}, {os.cpu_count()} cores; "
          f"{args.rounds} rounds, median of each round's mean")
    print()
    print("| device | slaves | increments | Rust (ms) | C (ms) | C / Rust | Python (ms) | Python / Rust | fastest rounds: C / Rust, Python / Rust | first call Rust / C / Python (ms) |")
    print("|---|---:|---:|---:|---:|---:|---:|---:|---|---|")
    for device in args.devices.split(","):
        for want in (int(s) for s in args.sizes.split(",")):
            reps = max(5, min(200, int(5e6 // want)))
            r, cc, py = [], [], []
            for _ in range(args.rounds):
                r.append(native(rust, device, want, reps))
                cc.append(native(c, device, want, reps))
                py.append(python_case(device, want, reps))
            med = lambda rows: statistics.median(row[2] for row in rows)  # noqa: E731
            first = lambda rows: statistics.median(row[1] for row in rows)  # noqa: E731
            low = lambda rows: min(row[2] for row in rows)  # noqa: E731
            mr, mc, mp = med(r), med(cc), med(py)
            print(
                f"| {device} | {r[0][0]:,} | {reps} | {mr * 1e3:.3f} | {mc * 1e3:.3f} | "
                f"{mc / mr:.3f} | {mp * 1e3:.3f} | {mp / mr:.3f} | "
                f"{low(cc) / low(r):.3f}, {low(py) / low(r):.3f} | "
                f"{first(r) * 1e3:.0f} / {first(cc) * 1e3:.0f} / {first(py) * 1e3:.0f} |",
                flush=True,
            )


if __name__ == "__main__":
    main()
