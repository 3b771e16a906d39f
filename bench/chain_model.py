#!/usr/bin/env python3
"""Writes the sparse bench's shear building as a study `rths run` takes (issue 63).

Inputs: N (DOFs), a folder, the record's seconds, the damping, optional recorders.
Outputs in the folder: mass.mtx (diagonal M = 1e5 kg a floor), stiffness.mtx (tridiagonal K of
storeys of 4e10 N/m, omega_max dt about 1.2 at dt = 1/1024 s), both Matrix Market coordinate real
symmetric (lower triangle), and chain.textproto: floor 1 a third experimental, explicit Newmark
at dt = 1/1024 s, the Imperial Valley record cut to the seconds asked, two cases (`reference`,
`lag` with a 2 ms shift). The same model as bench/sparse_bench.cpp's .mtx rows.

    bench/chain_model.py 1000 /tmp/chain1000 --seconds 2 [--damping modal] [--recorders TEXT]
    build/cli/rths run /tmp/chain1000/chain.textproto --no-plots --out /tmp/chain1000/out

--real-time DOMAIN adds a real-time deployment for `rths launch` (docs/performance.md): a
substructure node holds the numerical model (every DOF; `--model-on coordinator`: the coordinator
holds it), an actuator emulator the experimental DOF, at 1024 Hz, with the fail-safe windows and overrun tolerance of
configs/paper_frame_distributed.textproto (sized for a stock 2-core VM) and the loop on CPU 1.
"""

import argparse
import pathlib
import sys

FLOOR_MASS = 1e5  # kg
STOREY_STIFFNESS = 4e10  # N/m
REAL_TIME = """deployment {{
  domain_id: {domain}
  clock: REAL_TIME
{substructure}  nodes {{ id: 2 kind: ACTUATOR_EMULATOR }}
  answer_window_ms: 12
  command_watchdog_ms: 12
  max_overrun_fraction: 0.005
  pin_loop: true
  loop_cpu: 1
}}
"""
DAMPING = {
    "rayleigh": "rayleigh { zeta: 0.05 mode_i: 1 mode_j: 2 }",
    "modal": "modal_zeta: 0.05",
}


def write_market(path, n, entries):
    with open(path, "w", encoding="ascii") as out:
        out.write("%%MatrixMarket matrix coordinate real symmetric\n")
        out.write(f"{n} {n} {len(entries)}\n")
        for row, col, value in entries:
            out.write(f"{row} {col} {value!r}\n")


def main():
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("dofs", type=int)
    parser.add_argument("folder", type=pathlib.Path)
    parser.add_argument("--seconds", type=float, default=2.0, help="record cut to (s)")
    parser.add_argument("--damping", choices=sorted(DAMPING), default="rayleigh")
    parser.add_argument("--recorders", default="", help="recorders blocks, text format")
    parser.add_argument("--real-time", type=int, metavar="DOMAIN", help="add a real-time deployment")
    parser.add_argument("--model-on", choices=["node", "coordinator"], default="node")
    args = parser.parse_args()
    if args.dofs < 2 or not args.seconds > 0:
        sys.exit("chain_model.py: needs at least 2 DOFs and seconds > 0")
    n = args.dofs
    args.folder.mkdir(parents=True, exist_ok=True)
    write_market(args.folder / "mass.mtx", n, [(i, i, FLOOR_MASS) for i in range(1, n + 1)])
    stiffness = []
    for i in range(1, n + 1):
        stiffness.append((i, i, 2 * STOREY_STIFFNESS if i < n else STOREY_STIFFNESS))
        if i > 1:
            stiffness.append((i, i - 1, -STOREY_STIFFNESS))
    write_market(args.folder / "stiffness.mtx", n, stiffness)
    motion = pathlib.Path(__file__).resolve().parent.parent / "data" / "ground_motions"
    motion = motion / "RSN175_IMPVALL.H_H-E12140.AT2"
    (args.folder / "chain.textproto").write_text(
        f'name: "chain{n}"\n'
        'structure { matrices { mass { file: "mass.mtx" } stiffness { file: "stiffness.mtx" } }\n'
        f"  damping {{ {DAMPING[args.damping]} }} }}\n"
        f'motion {{ path: "{motion}" duration: {args.seconds} }}\n'
        "integrator { kind: EXPLICIT_NEWMARK dt: 0.0009765625 }\n"
        f"substructuring {{ experimental_dofs {{ dof: 1 stiffness: {STOREY_STIFFNESS / 3!r} }} }}\n"
        'cases { name: "reference" }\n'
        'cases { name: "lag" delay { shift { delay: 0.002 } } }\n'
        + args.recorders
        + "\n"
        + ("" if args.real_time is None else REAL_TIME.format(
                domain=args.real_time,
                substructure="  nodes { id: 1 kind: SUBSTRUCTURE }\n" if args.model_on == "node" else "",
            )),
        encoding="ascii",
    )


if __name__ == "__main__":
    main()
