#!/usr/bin/env python3
"""Compares abut's node output with CalculiX's reference results for the same deck.

    compare_dat_ref.py DECK.dat.ref[.gz] OUTPUT_DIR

CalculiX's `.dat.ref` holds its printed results: blocks headed
`displacements (vx,vy,vz) for set NAME and time T` followed by `label ux uy uz` rows. abut writes
a deck's `*NODE PRINT, NSET=NAME` request as `node-print-NAME.csv` (`time,node,U1,U2,U3,...`) at
the step's end. For each set in both, the last reference block is compared with abut's rows by
node label: the largest displacement difference over the largest reference displacement.

Prints one line, `<error> <set> <nodes>` (the error as a fraction), for the set with the largest
error; prints `- no common set` when there is nothing to compare.
"""
import csv
import gzip
import os
import re
import sys

HEAD = re.compile(r"^\s*displacements \(vx,vy,vz\) for set (\S+) and time\s+(\S+)")


def reference_blocks(path):
    """The last displacement block of each set: {set: {label: (ux, uy, uz)}}."""
    opener = gzip.open if path.endswith(".gz") else open
    blocks, current = {}, None
    with opener(path, "rt", errors="replace") as f:
        for line in f:
            m = HEAD.match(line)
            if m:
                current = {}
                blocks[m.group(1).upper()] = current
                continue
            parts = line.split()
            if current is not None and len(parts) == 4:
                try:
                    current[int(parts[0])] = tuple(float(v) for v in parts[1:])
                except ValueError:
                    current = None
            elif current is not None and parts:
                current = None
    return blocks


def abut_rows(path):
    with open(path, newline="") as f:
        return {
            int(r["node"]): (float(r["U1"]), float(r["U2"]), float(r["U3"]))
            for r in csv.DictReader(f)
        }


def main():
    ref_path, out = sys.argv[1], sys.argv[2]
    worst = None
    for name, ref in reference_blocks(ref_path).items():
        csv_path = os.path.join(out, f"node-print-{name}.csv")
        if not ref or not os.path.exists(csv_path):
            continue
        mine = abut_rows(csv_path)
        common = [k for k in ref if k in mine]
        if not common:
            continue
        scale = max(max(abs(v) for v in ref[k]) for k in common)
        diff = max(max(abs(a - b) for a, b in zip(ref[k], mine[k])) for k in common)
        err = diff / scale if scale > 0 else diff
        if worst is None or err > worst[0]:
            worst = (err, name, len(common))
    if worst is None:
        print("- no common set")
    else:
        print(f"{worst[0]:.3e} {worst[1]} {worst[2]}")


if __name__ == "__main__":
    main()
