#!/usr/bin/env python3
"""Compares a run's /strain with the strain in a truth.h5 (docs/validation.md, "Strain").

    compare_strain.py TRUTH.h5 LABEL=RESULTS.h5 [LABEL=RESULTS.h5 ...] [--rows R0:R1]

truth.h5 comes from `impactdic synth` (soil/dudx ...: the analytic Jacobian of the soil field) or
`impactdic synth --dem` (the least-squares affine fit of each subset's grains). Both hold the
strain under the names of results.h5's /strain. Samples compared: every frame after the first
reference, subsets with a converged DIC status, not covered by the pounder (soil/occluded, synth
only), finite in both files. Prints one Markdown table: RMS and max |error| per measure and
result, and, per result, the error of the Green-Lagrange quadratic term (H^T H / 2: GL minus
small strain) next to the RMS of that term in the truth (what dropping it would cost).
Needs numpy and h5py (Debian: python3-numpy python3-h5py).
"""
import argparse
import sys

import h5py
import numpy as np

MEASURES = ["dudx", "dudy", "dvdx", "dvdy", "exx", "eyy", "exy", "green_lagrange_xx",
            "green_lagrange_yy", "green_lagrange_xy", "eps_v", "gamma_max"]


def samples(truth, results, rows):
    """The mask [F x N] of the compared samples."""
    status = results["dic/status"][:]
    mask = status == 0
    mask[0, :] = False  # the first reference: zero by definition
    if "soil/occluded" in truth:
        mask &= truth["soil/occluded"][:].reshape(status.shape) == 0
    if rows is not None:
        r, c = truth["soil/grid_x_px"].shape
        row_of = np.repeat(np.arange(r), c)
        mask &= (row_of >= rows[0]) & (row_of < rows[1])
    return mask


def main():
    p = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    p.add_argument("truth")
    p.add_argument("results", nargs="+", help="LABEL=results.h5")
    p.add_argument("--rows", help="grid rows R0:R1 only (e.g. 2:8)")
    a = p.parse_args()
    rows = tuple(int(v) for v in a.rows.split(":")) if a.rows else None
    truth = h5py.File(a.truth, "r")
    runs = [r.split("=", 1) for r in a.results]
    cols = []
    for label, path in runs:
        res = h5py.File(path, "r")
        if "strain" not in res:
            sys.exit(f"{path}: no /strain group (scene key strain.enabled: true)")
        mask = samples(truth, res, rows)
        stats = {}
        for m in MEASURES:
            t = truth["soil/" + m][:].reshape(mask.shape)
            r = res["strain/" + m][:]
            ok = mask & np.isfinite(t) & np.isfinite(r)
            e = np.abs(r[ok] - t[ok])
            stats[m] = (np.sqrt(np.mean(e ** 2)), e.max(), int(ok.sum()))
        q_err, q_truth = [], []
        for gl, sm in (("green_lagrange_xx", "exx"), ("green_lagrange_yy", "eyy"),
                       ("green_lagrange_xy", "exy")):
            tq = (truth["soil/" + gl][:] - truth["soil/" + sm][:]).reshape(mask.shape)
            rq = res["strain/" + gl][:] - res["strain/" + sm][:]
            ok = mask & np.isfinite(tq) & np.isfinite(rq)
            q_err.append(rq[ok] - tq[ok])
            q_truth.append(tq[ok])
        q_err, q_truth = np.concatenate(q_err), np.concatenate(q_truth)
        stats["H^T H / 2 (GL - small)"] = (np.sqrt(np.mean(q_err ** 2)), np.abs(q_err).max(),
                                           q_err.size)
        stats["  its truth RMS, max"] = (np.sqrt(np.mean(q_truth ** 2)), np.abs(q_truth).max(),
                                         q_truth.size)
        cols.append((label, res["strain"].attrs.get("gradient", "?"), stats))
    names = list(cols[0][2].keys())
    print("| measure | " + " | ".join(f"{l} RMS | {l} max" for l, _, _ in cols) + " |")
    print("|---|" + "---|---|" * len(cols))
    for n in names:
        print(f"| {n} | " + " | ".join(f"{s[n][0]:.2e} | {s[n][1]:.2e}" for _, _, s in cols) + " |")
    print("samples: " + ", ".join(f"{l} {s['eps_v'][2]}" for l, _, s in cols))


if __name__ == "__main__":
    main()
