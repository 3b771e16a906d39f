#!/usr/bin/env python3
"""The source paper's Fig. 3 and Fig. 4 from Python, with the `rths` module and matplotlib.

Fig. 3: the paper's frame (T = 0.5 s, 5 % damping, El Centro 1979) without delay and with 14 ms
of actuator lag; the lag enlarges the response. Fig. 4: the delay error (NRMSE) against the
period, one line per delay, for a linear and a softening (bilinear) specimen; the error falls with
the period and is smaller for the softening specimen.

    PYTHONPATH=build/python python3 examples/paper_figures.py --out out/figures

Writes fig3_displacement.png and fig4_error_vs_period.png into --out and prints what it measured.
Headless by default (matplotlib's Agg backend); --periods thins the Fig. 4 grid for a quick run.
"""
import argparse
from pathlib import Path

import matplotlib

matplotlib.use("Agg")
import matplotlib.pyplot as plt  # noqa: E402
import numpy as np  # noqa: E402

import rths  # noqa: E402

CONFIGS = Path(__file__).resolve().parent.parent / "configs"


def figure3(out):
    result = rths.run(rths.load_study(CONFIGS / "paper_frame.textproto"), cases=["lag_shift_14ms"])
    s = result["series"]
    cases = {c["name"]: c for c in result["summary"]["cases"]}
    fig, (top, bottom) = plt.subplots(2, 1, figsize=(9, 6), sharex=True)
    top.plot(s["time_s"], 1e3 * s["reference_u_floor1_m"], color="black", lw=1.0, label="reference (no delay)")
    top.plot(s["time_s"], 1e3 * s["lag_shift_14ms_u_floor1_m"], color="tab:red", lw=0.8, label="14 ms actuator lag")
    top.set_ylabel("displacement (mm)")
    top.set_title("Fig. 3: the paper's frame, T = 0.5 s, 5 % damping, El Centro 1979")
    top.legend(loc="upper right")
    bottom.plot(s["time_s"], 1e3 * (s["lag_shift_14ms_u_floor1_m"] - s["reference_u_floor1_m"]), color="tab:red", lw=0.8)
    bottom.set_ylabel("error (mm)")
    bottom.set_xlabel("time (s)")
    bottom.set_title(f"error of the lagged test: NRMSE {cases['lag_shift_14ms']['nrmse_pct']:.0f} %")
    for axis in (top, bottom):
        axis.grid(alpha=0.3)
    fig.tight_layout()
    path = out / "fig3_displacement.png"
    fig.savefig(path, dpi=120)
    plt.close(fig)
    ratio = cases["lag_shift_14ms"]["peak_displacement_m"] / cases["reference"]["peak_displacement_m"]
    print(f"Fig. 3: peak {1e3 * cases['reference']['peak_displacement_m']:.2f} mm without delay, "
          f"{1e3 * cases['lag_shift_14ms']['peak_displacement_m']:.2f} mm with 14 ms lag (x{ratio:.2f}); {path}")
    return ratio


def figure4(out, every_nth_period):
    study = rths.load_study(CONFIGS / "paper_sweep.textproto")
    result = rths.sweep(study)
    s = result["series"]
    periods = np.unique(s["period_s"])[::every_nth_period]
    stiffness = np.min(s["stiffness_N_per_m"])  # the stiffnesses coincide at a fixed period
    models = list(dict.fromkeys(s["model"]))
    fig, axes = plt.subplots(1, len(models), figsize=(5.5 * len(models), 4.5), sharey=True, squeeze=False)
    for axis, model in zip(axes[0], models):
        for delay in np.unique(s["delay_s"]):
            pick = ((np.array(s["model"]) == model) & (s["delay_s"] == delay) & (s["stiffness_N_per_m"] == stiffness)
                    & np.isin(s["period_s"], periods))
            order = np.argsort(s["period_s"][pick])
            axis.semilogy(s["period_s"][pick][order], s["nrmse_pct"][pick][order], marker="o", ms=3,
                          label=f"{1e3 * delay:.0f} ms")
        axis.set_title(f"{model} specimen")
        axis.set_xlabel("period T (s)")
        axis.grid(alpha=0.3, which="both")
    axes[0][0].set_ylabel("NRMSE of the delayed test (%)")
    axes[0][-1].legend(title="delay", loc="upper right")
    diverged = int(np.sum(s["diverged"]))
    fig.suptitle("Fig. 4: the delay error falls with the period (El Centro 1979, 5 % damping)"
                 + (f"; {diverged} diverged points left out" if diverged else ""))
    fig.tight_layout()
    path = out / "fig4_error_vs_period.png"
    fig.savefig(path, dpi=120)
    plt.close(fig)
    trends = result["paper_trends"]  # the paper's NRMSE, as its Fig. 4 reads
    print(f"Fig. 4: {result['grid_points']} grid points; NRMSE falls between "
          f"{100 * trends['period_falling_pair_fraction']:.0f} % of consecutive periods; "
          f"bilinear / linear median NRMSE {trends['nonlinear_to_linear_median_ratio']:.2f}; {path}")
    return trends


def main():
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--out", type=Path, default=Path("out/figures"), help="folder for the PNGs")
    parser.add_argument("--periods", type=int, default=1, help="plot every n-th period of Fig. 4's grid")
    args = parser.parse_args()
    args.out.mkdir(parents=True, exist_ok=True)
    figure3(args.out)
    figure4(args.out, args.periods)


if __name__ == "__main__":
    main()
