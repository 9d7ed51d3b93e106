#!/usr/bin/env python3
"""Across MPI ranks: scenes/block_drop.toml at two sizes, run by `abut run` in one process and
under `mpirun -n 1, 2, 4, 8`, one line per run in a Markdown table (docs/BENCHMARKS.md).

Per rank, from each run's summary.json (`ranks`): peak resident memory (VmHWM), nodes owned and
held as halo, contact ghosts, bytes sent per increment (halo and contact) and MPI collectives
per increment; and the run's wall-clock time per increment after the first (every rank waits
for the slowest at each exchange). The CPU path with one thread per rank (RAYON_NUM_THREADS=1),
so that ranks share the cores alike.

    cargo build --release --features mpi
    python3 benches/mpi_ranks.py [--sizes 16,32] [--ranks 1,2,4,8] [--abut target/release/abut]
        [--enforce penalty|kinematic] [--sliding finite|small] [--plate fixed|free]

`--enforce kinematic` runs the contact pair kinematically (the master nodes' corrections summed
on their owners), `--sliding small` with small sliding (each slave anchored once); the bytes
then count the correction's exchanges too. `--plate free` makes the plate a free rigid body of
1,000 kg (its resultants summed over the ranks; under penalty every rank follows the whole body).
"""

import argparse
import json
import os
import pathlib
import re
import subprocess
import sys
import tempfile

ROOT = pathlib.Path(__file__).resolve().parent.parent


def scene(size: int, work: pathlib.Path, enforce: str, sliding: str, plate: str) -> pathlib.Path:
    """The committed scene with the block cut into size x size x size/2 hexahedra, its pair
    enforced and sliding as asked (kinematic small sliding is frictionless), its plate fixed or
    a free body."""
    text = (ROOT / "scenes" / "block_drop.toml").read_text()
    text, n = re.subn(
        r"divisions = \[16, 16, 8\]", f"divisions = [{size}, {size}, {size // 2}]", text
    )
    if n != 1:
        sys.exit("scenes/block_drop.toml: the block's divisions are not [16, 16, 8]")
    pair = "friction = 0.3"
    if enforce == "kinematic" and sliding == "small":
        pair = 'enforce = "kinematic"\nsliding = "small"'
    elif enforce == "kinematic":
        pair += '\nenforce = "kinematic"'
    elif sliding == "small":
        pair += '\nsliding = "small"'
    text = text.replace("friction = 0.3", pair)
    if plate == "free":
        text, n = re.subn(
            r"divisions = \[30, 30, 0\]",
            'divisions = [30, 30, 0]\nmotion = "free"\nmass = 1.0e3',
            text,
        )
        if n != 1:
            sys.exit("scenes/block_drop.toml: the plate's divisions are not [30, 30, 0]")
    path = work / f"block_drop_{size}_{enforce}_{sliding}_{plate}.toml"
    path.write_text(text)
    return path


def run(abut: str, toml: pathlib.Path, ranks: int, out: pathlib.Path) -> dict:
    """One run's summary: in one process (ranks 0) or under mpirun -n ranks."""
    cmd = [abut, "run", str(toml), "--backend", "cpu", "--output", str(out)]
    if ranks > 0:
        cmd = [
            "mpirun", "--allow-run-as-root", "--oversubscribe",
            "-x", "RAYON_NUM_THREADS", "-n", str(ranks),
        ] + cmd
    env = dict(os.environ, RAYON_NUM_THREADS="1")
    done = subprocess.run(cmd, env=env, capture_output=True, text=True, timeout=3600)
    if done.returncode != 0:
        sys.exit(f"{' '.join(cmd)} failed:\n{done.stdout[-2000:]}\n{done.stderr[-2000:]}")
    return json.loads((out / "summary.json").read_text())


def spread(values, fmt="{:,.0f}") -> str:
    lo, hi = min(values), max(values)
    return fmt.format(lo) if lo == hi else f"{fmt.format(lo)}–{fmt.format(hi)}"


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--sizes", default="16,32")
    ap.add_argument("--ranks", default="1,2,4,8")
    ap.add_argument("--abut", default=str(ROOT / "target" / "release" / "abut"))
    ap.add_argument("--enforce", choices=["penalty", "kinematic"], default="penalty")
    ap.add_argument("--sliding", choices=["finite", "small"], default="finite")
    ap.add_argument("--plate", choices=["fixed", "free"], default="fixed")
    args = ap.parse_args()
    sizes = [int(s) for s in args.sizes.split(",")]
    rank_counts = [int(r) for r in args.ranks.split(",")]
    print(
        "| N (tets) | ranks | ms per increment | increments | peak memory per rank, MB | "
        "own nodes per rank | halo nodes per rank | halo bytes per increment per rank | "
        "contact ghosts per rank | contact bytes per increment per rank | "
        "collectives per increment |"
    )
    print("|---|---|---|---|---|---|---|---|---|---|---|")
    with tempfile.TemporaryDirectory() as tmp:
        work = pathlib.Path(tmp)
        for size in sizes:
            toml = scene(size, work, args.enforce, args.sliding, args.plate)
            tets = 6 * size * size * (size // 2)
            for ranks in [0] + rank_counts:
                s = run(args.abut, toml, ranks, work / f"out-{size}-{ranks}")
                ms = 1e3 * s["seconds_per_increment"]
                label = f"{size} ({tets:,})" if ranks == 0 else ""
                if ranks == 0:
                    print(f"| {label} | single process | {ms:.2f} | {s['increments']} | – | – | – | – | – | – | – |")
                    continue
                r = s["ranks"]
                mem = [x["peak_resident_bytes"] / 2**20 for x in r]
                print(
                    f"| {label} | {ranks} | {ms:.2f} | {s['increments']} | {spread(mem, '{:.1f}')} "
                    f"| {spread([x['own_nodes'] for x in r])} "
                    f"| {spread([x['halo_nodes'] for x in r])} "
                    f"| {spread([x['halo_bytes_per_increment'] for x in r])} "
                    f"| {spread([x['contact_ghosts'] for x in r])} "
                    f"| {spread([x['contact_bytes_per_increment'] for x in r])} "
                    f"| {spread([x['collectives_per_increment'] for x in r], '{:.2f}')} |",
                    flush=True,
                )


if __name__ == "__main__":
    main()
