"""The paper's one-storey frame in OpenSeesPy, its column served by rths through genericClient.

First start the site:
    rths opensees-site examples/opensees/site_paper_frame.textproto --port 8090
then:
    python3 examples/opensees/one_storey_frame.py [--port 8090] [--out frame_disp.csv]
Units: m, kg, N, s. Writes the floor displacement per step (time_s, u_floor1_m).
"""
import argparse
import math
import pathlib
import re

import openseespy.opensees as ops

HERE = pathlib.Path(__file__).resolve().parent
RECORD = HERE / "../../data/ground_motions/RSN175_IMPVALL.H_H-E12140.AT2"


def read_at2(path):
    """(dt in s, accelerations in g) of a PEER AT2 file."""
    lines = pathlib.Path(path).read_text().splitlines()
    dt = float(re.search(r"DT=\s*([0-9.Ee+-]+)", lines[3]).group(1))
    return dt, [float(v) for line in lines[4:] for v in line.split()]


def main():
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--port", type=int, default=8090)
    parser.add_argument("--host", default="127.0.0.1")
    parser.add_argument("--duration", type=float, default=15.0, help="s of the record")
    parser.add_argument("--out", default="frame_disp.csv")
    args = parser.parse_args()

    period, mass, fraction, zeta, dt = 0.5, 1000.0, 0.3333333333333333, 0.05, 0.001
    omega = 2.0 * math.pi / period
    k = mass * omega * omega
    ops.wipe()
    ops.model("basic", "-ndm", 1, "-ndf", 1)
    ops.node(1, 0.0)
    ops.node(2, 0.0, "-mass", mass)
    ops.fix(1, 1)
    ops.uniaxialMaterial("Elastic", 1, (1.0 - fraction) * k)  # the numerical two thirds
    ops.element("zeroLength", 1, 1, 2, "-mat", 1, "-dir", 1)
    # The specimen column, served by rths: basic DOFs (u1, u2), one actuator on u2 - u1.
    ops.element("genericClient", 2, "-node", 1, 2, "-dof", 1, "-dof", 1,
                "-server", args.port, args.host, "-dataSize", 256)
    ops.rayleigh(2.0 * zeta * omega, 0.0, 0.0, 0.0)  # c = 2 zeta omega m

    dt_record, accel_g = read_at2(RECORD)
    ops.timeSeries("Path", 1, "-dt", dt_record, "-values", *accel_g, "-factor", 9.81)
    ops.pattern("UniformExcitation", 1, 1, "-accel", 1)
    ops.constraints("Plain")
    ops.numberer("Plain")
    ops.system("FullGeneral")
    ops.algorithm("Linear")
    ops.integrator("NewmarkExplicit", 0.5)  # one trial per step: what an actuator can follow
    ops.analysis("Transient")

    steps = int(round(args.duration / dt))
    with open(args.out, "w") as out:
        out.write("time_s,u_floor1_m\n")
        for _ in range(steps):
            if ops.analyze(1, dt) != 0:
                raise SystemExit("OpenSees: the analysis failed at t = %g s" % ops.getTime())
            out.write("%.6f,%.17g\n" % (ops.getTime(), ops.nodeDisp(2, 1)))
    ops.wipe()  # genericClient sends DIE (99): the site ends the run and closes the record


if __name__ == "__main__":
    main()
