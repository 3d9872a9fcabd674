#!/usr/bin/python3
"""Public benchmark images through `impactdic correlate`: every figure of the accuracy targets.

    bench/dic_challenge.py [--binary IMPACTDIC] [--data DIR] [--json FILE] [-- CORRELATE FLAGS...]

    bench/dic_challenge.py                                          # defaults
    bench/dic_challenge.py -- --max-uncertainty none --gaussian 0.8 # "best settings"

Everything after `--` is appended to every `impactdic correlate` command, so the same script
measures the defaults and any other settings (do not repeat the flags the script sets itself:
--mode, --subset, --step, --interp for Sample 3, --roi for Sample 12, --threads, -o).

DIR (default: $IMPACTDIC_SHARED_DATA, else ../shared/data beside the project root) is the public
benchmark folder described in its README.md; nothing of it is copied. Sections (--only, comma
separated: s3,s14,s12,sand,static,synth):

  s3    DIC Challenge 1.0 Sample 3 (dic-challenge/sample3): --mode pairs, subset 25, step 10, each
        rigid shift against the reference, bicubic and biquintic. Per shift: valid %, bias (mean
        error) and sd of u, v over the valid subsets, mean reported sigma, the ratio rms(sigma)/sd,
        and the noise limit from the zero-shift image; then max |bias| over shifts and components.
        Truth: the shift in the file name, X0.30 Y0.30 -> u = v = +0.30 px.
  s14   Sample 14 (dic-challenge/sample14): --mode pairs, subset 25, step 5, L1/L3/L5 against the
        reference. Truth: `Sample 14 Commanded Displacement.csv` (u per pixel column, linear in X
        between columns; v = 0). Per level: valid %, RMS error of u, v and 2-D over the valid
        subsets, the RMS over ALL subsets (n/a when any subset is invalid: an invalid subset has
        no value, so an RMS over all of them does not exist; the valid % says how many), the rms
        reported sigma and rms(sigma)/RMS(error) per component. v's error is noise alone; u's adds
        the shape function's error on the chirp (largest for L5), so sigma/error of v is the
        uncertainty check and that of u is a lower bound.
  s12   Sample 12 (dic-challenge/sample12) against DICe's results (gold/DICe_solution_NN.txt, a
        reference, not a truth): our grid placed on DICe's subset centres (its subset_size and
        step_size from input.xml; --roi from the extreme centres), --mode sequence (DICe solves
        each frame against image 00 from the previous frame's solution), oht_cfrp_00 the
        reference. Per frame: valid % of DICe's points, RMS and max |difference| of u and v at the
        points valid in both. DICe's settings differ (params.xml: Keys 4th-order interpolation,
        shape function translation + normal strain); the difference is not our error.
        Strain (correlate --warp-gradient): per frame, at DICe's points, the RMS and max
        |difference| of exx, eyy against DICe's VSG_STRAIN_XX, _YY (Green-Lagrange, a plane fitted
        to its displacements within the circle of diameter strain_window_size_in_pixels of
        params.xml, 360 px): ours is the Green-Lagrange strain of the mean of our warp gradients
        over our valid subsets at DICe's points in the same circle, and, raw, of the point's own
        subset; DICe's RMS strain for scale.
  sand  Real sand test48 (real-sand/test48, IMG_30..40, 4096x3000 JPEG): --mode sequence against
        IMG_30, subset 25, step 50 (--sand-step; 50 keeps the run short and the subsets apart, so
        that neighbouring results have independent noise), --roi 0,1400,4096,3000: the sand below
        its surface (above y = 1280..1340 px the frames show the tank's back wall through the
        glass, with glare; --sand-roi full for the whole image). Per frame: valid %, what the invalid
        ones are, median |displacement|, and the observed scatter against the reported sigma.
        There is no truth: each valid u (v) is compared with a quadratic least-squares fit of its
        valid neighbours in the 5x5 grid window (at least 12 of 24, the point itself left out),
        and the residual r is normalised by its predicted sd under the reported sigmas,
        z = r / sqrt(sigma_i^2 + sum_j w_j^2 sigma_j^2) (w: the fit's weights at the centre).
        rms(z) is observed scatter / reported sigma (1 = right, 2 = sigma half the scatter), with
        |z| > 5 robust sd dropped as outliers (their share is printed) and 1.4826 MAD(z) beside
        it; "scatter" is sqrt(mean r^2 / (1 + h)), h = sum w_j^2, the noise sd the residuals imply
        if all subsets had the same one. Smooth motion (the pipe's uplift) is in the fit, not in r.
  static Real static sand (real-sand/static, IMG_1..5, 4096x3000 JPEG, the camera and the sand at
        rest): --mode pairs, IMG_1 against each of IMG_2..5, subset 25, step 50 (independent
        subsets), the sand ROI of `sand`. Truth: no motion but a smooth apparent one (the frames
        drift by a few hundredths of a pixel across the field), so each component's residual is
        taken from a quadratic surface fitted to all valid subsets of the pair (6 parameters
        against ~2,900 points), with |residual| > 5 robust sd dropped (their share printed). The
        sigma check compares like with like: rms(reported sigma) / sd(residual) over the same
        subsets, for all of them and within each quartile of the reported sigma (the sigma
        varies 4x over these frames, with the lighting; a calibrated sigma matches in every
        quartile). The median sigma against the sd of all subsets is printed beside it: it is not
        a calibration figure (sd^2 is the mean of the sigma^2, which the large sigmas at the
        frame's edges dominate), and it reads 0.6 on these frames where the sigma is right.
  synth Synthetic noise, made here (numpy): a band-limited speckle (white noise through a Gaussian
        of 1.5 px sd, 30 grey levels sd about 128), shifted exactly by the Fourier shift theorem,
        Gaussian noise of 2 and 5 grey levels added to every image (reference too), 8-bit TIFF.
        --mode pairs, subset 25, step 25 (independent subsets). Truth: the shift. Per image:
        valid %, bias, sd, rms sigma, rms(sigma)/sd.

Where a figure cannot be measured (data absent, correlate failed, no valid subset) the cell says
n/a and a note below the table says why; a number is never made up from a failure.
--check prints the issue's targets (measured, required, PASS/FAIL); --quick leaves out what the
targets test does not need (Sample 14 L3 and L5, the synthetic 5 grey levels; about 15 s instead
of 30 s on 2 cores), with the same settings otherwise.

Exit status: 0 every requested figure measured; 1 some could not be (the notes say why);
2 bad arguments or no executable binary.
"""

import argparse
import csv
import json
import math
import os
import re
import shlex
import subprocess
import sys
import tempfile
import time

sys.dont_write_bytecode = True  # no __pycache__ in the source tree
sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))
import tiff_lite  # noqa: E402

try:
    import numpy as np
except ImportError:  # Debian's python3-numpy (scripts/install_deps.sh) is for /usr/bin/python3
    sys.exit("dic_challenge: error: numpy is missing: run with /usr/bin/python3 (Debian's "
             "python3-numpy, installed by scripts/install_deps.sh)")

ROOT = os.path.dirname(os.path.dirname(os.path.abspath(__file__)))
DEFAULT_DATA = os.environ.get("IMPACTDIC_SHARED_DATA") or os.path.join(ROOT, "..", "shared", "data")
SECTIONS = ("s3", "s14", "s12", "sand", "static", "synth")

S3_REFERENCE = re.compile(r"^sample\s*3 reference\.tiff?$", re.I)
S3_DEFORMED = re.compile(r"^sample\s*3-(\d+) x(-?\d+(?:\.\d+)?) y(-?\d+(?:\.\d+)?)\b.*\.tiff?$", re.I)
S14_REFERENCE = re.compile(r"^sample\s*14 reference\.tiff?$", re.I)
S14_DEFORMED = re.compile(r"^sample\s*14 l(\d+) amp(\d+(?:\.\d+)?)[a-z]?\.tiff?$", re.I)
S14_TRUTH = "Sample 14 Commanded Displacement.csv"

# The accuracy targets (--check). The tests assert their own copy.
TARGET_S3_MAX_BIAS_PX = 0.001
TARGET_SIGMA_RATIO = (0.7, 1.3)  # reported sigma within +-30 % of the observed scatter
TARGET_SAND_VALID_PERCENT = 98.0

# Real sand test48: the sand below its surface (the frames' top 1280-1340 px show the tank's back
# wall behind the glass, with glare, not sand).
SAND_ROI = "0,1400,4096,3000"


class Unmeasurable(Exception):
    """A section or figure that cannot be measured; the message says why."""


# ---------------------------------------------------------------- small helpers

NA = float("nan")


def fmt(x, digits=4):
    if x is None or (isinstance(x, float) and math.isnan(x)):
        return "n/a"
    return f"{x:.{digits}f}"


def sci(x):
    return "n/a" if x is None or math.isnan(x) else f"{x:.2e}"


def pct(x):
    return "n/a" if x is None or math.isnan(x) else f"{x:.1f} %"


def quote(s):
    return shlex.quote(s)


def rms(a):
    a = np.asarray(a, float)
    return float(np.sqrt(np.mean(a * a))) if a.size else NA


def mean(a):
    a = np.asarray(a, float)
    return float(np.mean(a)) if a.size else NA


def sd(a):
    a = np.asarray(a, float)
    return float(np.std(a, ddof=1)) if a.size >= 2 else NA


def ratio(a, b):
    return a / b if b and not math.isnan(a) and not math.isnan(b) else NA


def jsonable(x):
    if isinstance(x, dict):
        return {k: jsonable(v) for k, v in x.items()}
    if isinstance(x, (list, tuple)):
        return [jsonable(v) for v in x]
    if isinstance(x, (float, np.floating)):
        return None if math.isnan(x) else float(x)
    if isinstance(x, np.integer):
        return int(x)
    return x


def find(folder, pattern):
    hits = []
    for root, _, files in os.walk(folder):
        for name in files:
            m = pattern.match(name)
            if m:
                hits.append((os.path.join(root, name), m))
    return sorted(hits, key=lambda h: h[0])


def need_folder(path, what):
    if not os.path.isdir(path):
        raise Unmeasurable(f"{what}: no folder {path} (the shared benchmark data; --data DIR or "
                           f"IMPACTDIC_SHARED_DATA)")
    return path


class Frame:
    """One frame's results of a correlate CSV, as arrays."""

    def __init__(self, label, rows):
        self.label = label
        self.x = np.array([float(r["x_px"]) for r in rows])
        self.y = np.array([float(r["y_px"]) for r in rows])
        self.u = np.array([float(r["u_px"]) for r in rows])
        self.v = np.array([float(r["v_px"]) for r in rows])
        self.su = np.array([float(r["sigma_u_px"]) for r in rows])
        self.sv = np.array([float(r["sigma_v_px"]) for r in rows])
        self.status = np.array([r["status"] for r in rows])
        # Valid: status converged (the library's IsValidStatus) with finite values.
        self.valid = (self.status == "converged") & np.isfinite(self.u) & np.isfinite(self.v)
        # The subset warp's gradient (correlate --warp-gradient); NaN without it.
        self.grad = {c: np.array([float(r.get(c + "_warp") or "nan") for r in rows])
                     for c in ("dudx", "dudy", "dvdx", "dvdy")}

    @property
    def valid_percent(self):
        return 100.0 * self.valid.sum() / self.valid.size if self.valid.size else NA

    def invalid_summary(self):
        names, counts = np.unique(self.status[~self.valid], return_counts=True)
        return ", ".join(f"{n} {c}" for n, c in sorted(zip(names, counts), key=lambda t: -t[1])) or "-"


class Runner:
    def __init__(self, binary, extra, threads, work):
        self.binary, self.extra, self.threads, self.work = binary, extra, threads, work
        self.commands = []
        self.warnings = []

    def correlate(self, name, inputs, flags, count):
        """Runs correlate; returns `count` Frames in file order (the reference has no rows)."""
        out = os.path.join(self.work, name + ".csv")
        cmd = [self.binary, "-q", "correlate", *inputs, *flags, "--threads", str(self.threads),
               *self.extra, "-o", out]
        t0 = time.monotonic()
        proc = subprocess.run(cmd, capture_output=True, text=True)
        seconds = time.monotonic() - t0
        shown = " ".join(quote(c) for c in cmd)
        self.commands.append((name, shown, seconds))
        if proc.returncode != 0:
            tail = "\n".join((proc.stdout + proc.stderr).strip().splitlines()[-5:])
            raise Unmeasurable(f"impactdic correlate failed (exit {proc.returncode}): {shown}\n{tail}")
        with open(out, newline="") as f:
            rows = list(csv.DictReader(f))
        for col in ("frame", "x_px", "y_px", "u_px", "v_px", "status", "sigma_u_px", "sigma_v_px"):
            if not rows or col not in rows[0]:
                raise Unmeasurable(f"{out}: no column '{col}' or no rows (correlate's CSV changed?)")
        groups, order = {}, []
        for r in rows:
            if r["frame"] not in groups:
                groups[r["frame"]] = []
                order.append(r["frame"])
            groups[r["frame"]].append(r)
        if len(order) != count:
            raise Unmeasurable(f"{out}: {len(order)} frames of results for {count} deformed images")
        frames = [Frame(k, groups[k]) for k in order]
        no_sigma = sum(int((f.valid & ~(np.isfinite(f.su) & np.isfinite(f.sv))).sum()) for f in frames)
        if no_sigma:
            self.warnings.append(f"{name}: {no_sigma} valid subsets without a finite sigma_u/v: "
                                 f"the sigma figures of that section are n/a")
        return frames, seconds


def notes_block(notes):
    for n in notes:
        print("note: " + n)
    if notes:
        print()


# ---------------------------------------------------------------- Sample 3

def gradient_sums(img, half):
    """Per pixel: sums over the (2 half + 1)^2 box of (dI/dx)^2 and (dI/dy)^2 (central
    differences), via summed-area tables (box clipped at the border)."""
    gx = np.zeros_like(img)
    gy = np.zeros_like(img)
    gx[:, 1:-1] = (img[:, 2:] - img[:, :-2]) / 2
    gy[1:-1, :] = (img[2:, :] - img[:-2, :]) / 2

    def box(a):
        s = np.zeros((a.shape[0] + 1, a.shape[1] + 1))
        s[1:, 1:] = np.cumsum(np.cumsum(a, 0), 1)
        h, w = a.shape
        y0 = np.clip(np.arange(h) - half, 0, h)
        y1 = np.clip(np.arange(h) + half + 1, 0, h)
        x0 = np.clip(np.arange(w) - half, 0, w)
        x1 = np.clip(np.arange(w) + half + 1, 0, w)
        return s[y1][:, x1] - s[y0][:, x1] - s[y1][:, x0] + s[y0][:, x0]

    return box(gx * gx), box(gy * gy)


def read_grey(path):
    img = tiff_lite.read_tiff(path)
    return np.array(img.pixels, float).reshape(img.height, img.width)


def sample3(ctx):
    folder = need_folder(os.path.join(ctx.data, "dic-challenge", "sample3"), "Sample 3")
    refs = find(folder, S3_REFERENCE)
    if len(refs) != 1:
        raise Unmeasurable(f"Sample 3: expected one 'Sample3 Reference.tif' under {folder}, found {len(refs)}")
    reference = refs[0][0]
    deformed = [(p, float(m.group(2)), float(m.group(3))) for p, m in find(folder, S3_DEFORMED)]
    if not deformed:
        raise Unmeasurable(f"Sample 3: no shifted images 'Sample3-NNN X.. Y.. ....tif' under {folder}")
    subset, step = ctx.args.s3_subset, ctx.args.s3_step
    interps = ("bicubic", "biquintic")
    print(f"## DIC Challenge 1.0 Sample 3 (pairs, subset {subset}, step {step})\n")
    notes, out = [], {"subset": subset, "step": step, "interpolators": {}}
    # Noise limit: sigma_n from the zero-shift image (the same pattern with its own noise).
    limit_u = limit_v = None
    zero = [d for d in deformed if d[1] == 0 and d[2] == 0]
    try:
        if not zero:
            raise tiff_lite.TiffError("no zero-shift image (X0.00 Y0.00) to estimate the noise from")
        ref_img, zero_img = read_grey(reference), read_grey(zero[0][0])
        if ref_img.shape != zero_img.shape:
            raise tiff_lite.TiffError(f"{zero[0][0]}: size differs from the reference")
        sigma_n = float(np.std(ref_img - zero_img, ddof=1) / math.sqrt(2))
        sxx, syy = gradient_sums(ref_img, subset // 2)

        def limit(sums):
            def at_valid(fr):
                y, x = fr.y[fr.valid].astype(int), fr.x[fr.valid].astype(int)
                return rms(np.sqrt(2) * sigma_n / np.sqrt(sums[y, x]))
            return at_valid

        limit_u, limit_v = limit(sxx), limit(syy)
        print(f"Image noise sigma_n = {sigma_n:.3f} grey levels = sd(reference - "
              f"'{os.path.basename(zero[0][0])}') / sqrt(2). Noise limit = rms over the valid "
              f"subsets of sqrt(2) sigma_n / sqrt(sum (dI/dx)^2) (dI/dy for v): the sd noise "
              f"alone gives. sigma/sd = rms(reported sigma) / sd of the error, per component.\n")
        out["noise_sigma_grey"] = sigma_n
    except (tiff_lite.TiffError, OSError, KeyError) as e:
        notes.append(f"noise limit n/a: {e}")
    ok = True
    for interp in interps:
        print(f"### Sample 3, {interp}\n")
        print("| shift u, v [px] | valid | bias u [px] | bias v [px] | sd u [px] | sd v [px] | "
              "mean sigma u, v [px] | sigma/sd u, v | noise limit u, v [px] |")
        print("|---|---|---|---|---|---|---|---|---|")
        rows_out = []
        try:
            frames, seconds = ctx.run.correlate(
                f"s3_{interp}", ["--reference", reference, "--deformed", *[d[0] for d in deformed]],
                ["--mode", "pairs", "--subset", str(subset), "--step", str(step), "--interp", interp],
                len(deformed))
        except Unmeasurable as e:
            print("| n/a | n/a | n/a | n/a | n/a | n/a | n/a | n/a | n/a |\n")
            notes.append(f"{interp}: {e}")
            out["interpolators"][interp] = {"error": str(e)}
            ok = False
            continue
        for (path, su, sv), fr in zip(deformed, frames):
            m = fr.valid
            eu, ev = fr.u[m] - su, fr.v[m] - sv
            r = {"shift": [su, sv], "valid_percent": fr.valid_percent, "bias_u": mean(eu),
                 "bias_v": mean(ev), "sd_u": sd(eu), "sd_v": sd(ev),
                 "mean_sigma_u": mean(fr.su[m]), "mean_sigma_v": mean(fr.sv[m]),
                 "ratio_u": ratio(rms(fr.su[m]), sd(eu)), "ratio_v": ratio(rms(fr.sv[m]), sd(ev)),
                 "limit_u": limit_u(fr) if limit_u and m.any() else NA,
                 "limit_v": limit_v(fr) if limit_v and m.any() else NA}
            if not m.any():
                notes.append(f"{interp} {os.path.basename(path)}: no valid subset ({fr.invalid_summary()})")
            elif (su or sv) and abs(mean(fr.u[m]) + su) < abs(r["bias_u"]):
                notes.append(f"{os.path.basename(path)}: the measured shift is closer to the "
                             f"opposite of the name's: the sign convention assumed may be wrong")
            rows_out.append(r)
            print(f"| {su:.2f}, {sv:.2f} | {pct(r['valid_percent'])} | {fmt(r['bias_u'])} | "
                  f"{fmt(r['bias_v'])} | {fmt(r['sd_u'])} | {fmt(r['sd_v'])} | "
                  f"{fmt(r['mean_sigma_u'])}, {fmt(r['mean_sigma_v'])} | {fmt(r['ratio_u'], 2)}, "
                  f"{fmt(r['ratio_v'], 2)} | {fmt(r['limit_u'])}, {fmt(r['limit_v'])} |")
        biases = [abs(r[k]) for r in rows_out for k in ("bias_u", "bias_v")]
        max_bias = NA if not biases or any(math.isnan(b) for b in biases) else max(biases)
        ratios = [r[k] for r in rows_out for k in ("ratio_u", "ratio_v") if not math.isnan(r[k])]
        valid = min((r["valid_percent"] for r in rows_out), default=NA)
        print(f"\n{interp}: max |bias| {fmt(max_bias)} px"
              f"{' (n/a: a shift without valid subsets)' if math.isnan(max_bias) else ''}; "
              f"sigma/sd {fmt(min(ratios), 2) if ratios else 'n/a'}..{fmt(max(ratios), 2) if ratios else 'n/a'}; "
              f"lowest valid {pct(valid)}; {seconds:.1f} s\n")
        out["interpolators"][interp] = {"rows": rows_out, "max_abs_bias_px": max_bias,
                                        "sigma_ratio_min": min(ratios) if ratios else NA,
                                        "sigma_ratio_max": max(ratios) if ratios else NA,
                                        "min_valid_percent": valid, "seconds": seconds}
        if math.isnan(max_bias):
            ok = False
    notes_block(notes)
    out["notes"] = notes
    return out, ok


# ---------------------------------------------------------------- Sample 14

def read_s14_truth(path):
    """{level: u per integer x} from the challenge's table: three header lines, then rows
    x, L1 u, L1 exx, L3 u, L3 exx, L5 u, L5 exx (exx unused)."""
    table, x_expected = {1: [], 3: [], 5: []}, 0
    with open(path, newline="") as f:
        for n, row in enumerate(csv.reader(f), start=1):
            try:
                values = [float(c) for c in row[:7]]
            except ValueError:
                continue  # header lines
            if len(values) < 7 or int(values[0]) != x_expected:
                raise Unmeasurable(f"{path}: line {n}: expected x = {x_expected} and 7 columns")
            x_expected += 1
            for level, col in ((1, 1), (3, 3), (5, 5)):
                table[level].append(values[col])
    if x_expected < 2:
        raise Unmeasurable(f"{path}: no numeric rows")
    return {k: np.array(v) for k, v in table.items()}


def sample14(ctx):
    folder = need_folder(os.path.join(ctx.data, "dic-challenge", "sample14"), "Sample 14")
    refs = find(folder, S14_REFERENCE)
    if len(refs) != 1:
        raise Unmeasurable(f"Sample 14: expected one 'Sample14 Reference.tif' under {folder}, found {len(refs)}")
    deformed = [(p, int(m.group(1))) for p, m in find(folder, S14_DEFORMED)]
    if ctx.quick:
        deformed = [d for d in deformed if d[1] == 1]
    if not deformed:
        raise Unmeasurable(f"Sample 14: no 'Sample 14 L<k> Amp<A>.tif' under {folder}")
    truth_path = os.path.join(folder, S14_TRUTH)
    truth = read_s14_truth(truth_path)
    subset, step = ctx.args.s14_subset, ctx.args.s14_step
    roi = ctx.args.s14_roi
    sizes = {tiff_lite.read_size(p) for p in [refs[0][0]] + [d[0] for d in deformed]}
    if len(sizes) != 1:
        raise Unmeasurable(f"Sample 14: images of different sizes {sorted(sizes)}")
    flags = ["--mode", "pairs", "--subset", str(subset), "--step", str(step)]
    if roi:
        flags += ["--roi", roi]
    print(f"## DIC Challenge 1.0 Sample 14 (pairs, subset {subset}, step {step}"
          f"{', ROI ' + roi if roi else ''})\n")
    print(f"Truth: u from '{S14_TRUTH}' (linear between pixel columns), v = 0. RMS over the valid "
          f"subsets; `all` is the RMS over every subset of the grid, n/a when some are invalid. "
          f"sigma/err = rms(reported sigma) / RMS error (v: noise alone; u: noise + the shape "
          f"function's error on the chirp).\n")
    print("| image | valid | RMS err u [px] | RMS err v [px] | RMS 2-D [px] | RMS 2-D all [px] | "
          "rms sigma u, v [px] | sigma/err u | sigma/err v |")
    print("|---|---|---|---|---|---|---|---|---|")
    notes, rows_out, ok = [], [], True
    try:
        frames, seconds = ctx.run.correlate("s14", ["--reference", refs[0][0], "--deformed",
                                                    *[d[0] for d in deformed]], flags, len(deformed))
    except Unmeasurable as e:
        print("| n/a | n/a | n/a | n/a | n/a | n/a | n/a | n/a | n/a |\n")
        notes_block([str(e)])
        return {"error": str(e), "notes": [str(e)]}, False
    for (path, level), fr in zip(deformed, frames):
        name = os.path.basename(path)
        m = fr.valid
        if level in truth:
            col = truth[level]
            u_true = np.interp(fr.x, np.arange(col.size), col)
            eu, ev = fr.u[m] - u_true[m], fr.v[m]
        else:
            eu, ev = np.array([]), fr.v[m]
            notes.append(f"{name}: no commanded u for L{level} in the table (L1, L3, L5): u n/a")
        if not m.any():
            notes.append(f"{name}: no valid subset ({fr.invalid_summary()})")
            ok = False
        r = {"image": name, "level": level, "valid_percent": fr.valid_percent,
             "rms_err_u": rms(eu), "rms_err_v": rms(ev),
             "rms_err_2d": math.sqrt(rms(eu) ** 2 + rms(ev) ** 2),
             "rms_sigma_u": rms(fr.su[m]), "rms_sigma_v": rms(fr.sv[m])}
        r["rms_err_2d_all"] = r["rms_err_2d"] if m.all() else NA
        if not m.all():
            notes.append(f"{name}: RMS over all subsets n/a: {int((~m).sum())} of {m.size} "
                         f"invalid ({fr.invalid_summary()})")
        r["ratio_u"] = ratio(r["rms_sigma_u"], r["rms_err_u"])
        r["ratio_v"] = ratio(r["rms_sigma_v"], r["rms_err_v"])
        rows_out.append(r)
        print(f"| {name} | {pct(r['valid_percent'])} | {fmt(r['rms_err_u'])} | "
              f"{fmt(r['rms_err_v'])} | {fmt(r['rms_err_2d'])} | {fmt(r['rms_err_2d_all'])} | "
              f"{fmt(r['rms_sigma_u'])}, {fmt(r['rms_sigma_v'])} | {fmt(r['ratio_u'], 2)} | "
              f"{fmt(r['ratio_v'], 2)} |")
    print(f"\n{seconds:.1f} s\n")
    notes_block(notes)
    return {"subset": subset, "step": step, "roi": roi, "rows": rows_out, "notes": notes,
            "seconds": seconds}, ok


# ---------------------------------------------------------------- Sample 12

def read_dice_solution(path):
    """Columns of a DICe_solution_NN.txt (comment lines '***', one header line, comma rows)."""
    with open(path) as f:
        lines = [ln.strip() for ln in f if ln.strip() and not ln.startswith("***")]
    if not lines:
        raise Unmeasurable(f"{path}: no header")
    header = [h.strip() for h in lines[0].split(",")]
    data = np.array([[float(c) for c in ln.split(",")] for ln in lines[1:]])
    need = ("COORDINATE_X", "COORDINATE_Y", "DISPLACEMENT_X", "DISPLACEMENT_Y")
    if any(n not in header for n in need) or data.ndim != 2 or data.shape[1] != len(header):
        raise Unmeasurable(f"{path}: expected the columns {need} (found {header})")
    return {h: data[:, i] for i, h in enumerate(header)}


def xml_int(path, name):
    with open(path) as f:
        m = re.search(r'name="' + name + r'"[^>]*value="(-?\d+)"', f.read())
    if not m:
        raise Unmeasurable(f"{path}: no parameter {name}")
    return int(m.group(1))


def sample12(ctx):
    folder = need_folder(os.path.join(ctx.data, "dic-challenge", "sample12"), "Sample 12")
    images = sorted(os.path.join(folder, "images", n) for n in os.listdir(os.path.join(folder, "images"))
                    if re.fullmatch(r"oht_cfrp_\d+\.tiff?", n))
    subset = xml_int(os.path.join(folder, "input.xml"), "subset_size")
    step = xml_int(os.path.join(folder, "input.xml"), "step_size")
    ref_index = xml_int(os.path.join(folder, "input.xml"), "reference_image_index")
    gold = {}
    for n in sorted(os.listdir(os.path.join(folder, "gold"))):
        m = re.fullmatch(r"DICe_solution_(\d+)\.txt", n)
        if m:
            gold[int(m.group(1))] = read_dice_solution(os.path.join(folder, "gold", n))
    if not gold or len(images) <= max(gold):
        raise Unmeasurable(f"Sample 12: {len(gold)} gold files for {len(images)} images in {folder}")
    xs = np.concatenate([g["COORDINATE_X"] for g in gold.values()])
    ys = np.concatenate([g["COORDINATE_Y"] for g in gold.values()])
    half = subset // 2
    x0, y0 = int(xs.min()) - half, int(ys.min()) - half
    roi = f"{x0},{y0},{int(xs.max()) + half + 1},{int(ys.max()) + half + 1}"
    frames_idx = sorted(gold)
    deformed = [images[k] for k in frames_idx]
    print(f"## DIC Challenge 1.0 Sample 12 against DICe's results (sequence, subset {subset}, "
          f"step {step}, ROI {roi}: our grid on DICe's subset centres)\n")
    print(f"Reference {os.path.basename(images[ref_index])}; DICe's solution NN is image NN against "
          f"it. Differences at the points valid in both; valid = ours at DICe's points (DICe's "
          f"own failures, MATCH != 0, are left out).\n")
    print("| frame | DICe points | valid | RMS diff u [px] | RMS diff v [px] | max diff u [px] | "
          "max diff v [px] | DICe max |u|, |v| [px] | rms sigma u, v [px] |")
    print("|---|---|---|---|---|---|---|---|---|")
    notes, rows_out, ok = [], [], True
    try:
        frames, seconds = ctx.run.correlate(
            "s12", ["--reference", images[ref_index], "--deformed", *deformed],
            ["--mode", "sequence", "--subset", str(subset), "--step", str(step), "--roi", roi,
             "--warp-gradient"],
            len(deformed))
    except Unmeasurable as e:
        print("| n/a | n/a | n/a | n/a | n/a | n/a | n/a | n/a | n/a |\n")
        notes_block([str(e)])
        return {"error": str(e), "notes": [str(e)]}, False
    for k, fr in zip(frames_idx, frames):
        g = gold[k]
        good = g.get("MATCH", np.zeros_like(g["COORDINATE_X"])) == 0
        ours = {(int(round(x)), int(round(y))): i for i, (x, y) in enumerate(zip(fr.x, fr.y))}
        gx, gy = g["COORDINATE_X"][good], g["COORDINATE_Y"][good]
        at = np.array([ours.get((int(round(x)), int(round(y))), -1) for x, y in zip(gx, gy)], int)
        on = at >= 0
        if not on.all():
            notes.append(f"frame {k}: {int((~on).sum())} of DICe's points are not on our grid")
        idx, gu, gv = at[on], g["DISPLACEMENT_X"][good][on], g["DISPLACEMENT_Y"][good][on]
        v_ok = fr.valid[idx] if idx.size else np.array([], bool)
        du = fr.u[idx][v_ok] - gu[v_ok]
        dv = fr.v[idx][v_ok] - gv[v_ok]
        valid = 100.0 * v_ok.sum() / good.sum() if good.sum() else NA
        if not v_ok.any():
            notes.append(f"frame {k}: no valid subset at DICe's points")
            ok = False
        r = {"frame": k, "dice_points": int(good.sum()), "valid_percent": valid,
             "rms_diff_u": rms(du), "rms_diff_v": rms(dv),
             "max_diff_u": float(np.max(np.abs(du))) if du.size else NA,
             "max_diff_v": float(np.max(np.abs(dv))) if dv.size else NA,
             "dice_max_u": float(np.max(np.abs(gu))), "dice_max_v": float(np.max(np.abs(gv))),
             "rms_sigma_u": rms(fr.su[idx][v_ok]), "rms_sigma_v": rms(fr.sv[idx][v_ok])}
        rows_out.append(r)
        print(f"| {k} | {r['dice_points']} | {pct(valid)} | {fmt(r['rms_diff_u'])} | "
              f"{fmt(r['rms_diff_v'])} | {fmt(r['max_diff_u'])} | {fmt(r['max_diff_v'])} | "
              f"{fmt(r['dice_max_u'], 2)}, {fmt(r['dice_max_v'], 2)} | "
              f"{fmt(r['rms_sigma_u'])}, {fmt(r['rms_sigma_v'])} |")
    print(f"\n{seconds:.1f} s\n")
    notes_block(notes)
    window = xml_int(os.path.join(folder, "params.xml"), "strain_window_size_in_pixels")
    strain_rows, strain_ok = s12_strain_table(frames_idx, frames, gold, window)
    return {"subset": subset, "step": step, "roi": roi, "rows": rows_out, "notes": notes,
            "seconds": seconds, "strain_window_px": window,
            "strain_rows": strain_rows}, ok and strain_ok


def max_abs(a):
    return float(np.max(np.abs(a))) if a.size else NA


def green_lagrange(dudx, dudy, dvdx, dvdy):
    """E_xx, E_yy of H = [[dudx, dudy], [dvdx, dvdy]]: E = (H + H^T + H^T H) / 2."""
    return dudx + (dudx * dudx + dvdx * dvdx) / 2, dvdy + (dudy * dudy + dvdy * dvdy) / 2


def dice_gauge(gx, gy, u, v, valid, window):
    """DICe's VSG strain of displacements u, v at the points gx, gy: per point, the least-squares
    plane u = a + b dx + c dy of the valid points within window / 2 of it, E_xx, E_yy
    (Green-Lagrange) of the planes' slopes; NaN below 3 valid points."""
    exx, eyy = np.full(gx.size, NA), np.full(gx.size, NA)
    for i in range(gx.size):
        near = valid & ((gx - gx[i]) ** 2 + (gy - gy[i]) ** 2 <= (window / 2) ** 2 + 1e-5)
        if near.sum() < 3:
            continue
        x = np.column_stack([np.ones(near.sum()), gx[near] - gx[i], gy[near] - gy[i]])
        (_, dudx, dudy), (_, dvdx, dvdy) = (np.linalg.lstsq(x, w[near], rcond=None)[0]
                                            for w in (u, v))
        exx[i], eyy[i] = green_lagrange(dudx, dudy, dvdx, dvdy)
    return exx, eyy


def s12_strain(fr, g, window):
    """At DICe's points (MATCH == 0) where our subset is valid with a warp gradient: DICe's
    VSG_STRAIN_XX, _YY, ours from the window mean of our warp gradients (our valid subsets at
    DICe's points within the circle of diameter `window` about the point, DICe's neighbourhood)
    and ours from the point's own subset; all Green-Lagrange."""
    ours = {(int(round(x)), int(round(y))): i for i, (x, y) in enumerate(zip(fr.x, fr.y))}
    gx, gy = g["COORDINATE_X"], g["COORDINATE_Y"]
    at = np.array([ours.get((int(round(x)), int(round(y))), -1) for x, y in zip(gx, gy)], int)
    grad = {c: np.where(at >= 0, a[np.maximum(at, 0)], NA) for c, a in fr.grad.items()}
    member = (at >= 0) & fr.valid[np.maximum(at, 0)]
    member &= np.all([np.isfinite(a) for a in grad.values()], axis=0)
    points = member & (g.get("MATCH", np.zeros_like(gx)) == 0)
    win = {c: np.full(gx.size, NA) for c in grad}
    for i in np.flatnonzero(points):
        near = member & ((gx - gx[i]) ** 2 + (gy - gy[i]) ** 2 <= (window / 2) ** 2 + 1e-5)
        for c, a in grad.items():
            win[c][i] = np.mean(a[near])
    wxx, wyy = green_lagrange(*(win[c][points] for c in ("dudx", "dudy", "dvdx", "dvdy")))
    rxx, ryy = green_lagrange(*(grad[c][points] for c in ("dudx", "dudy", "dvdx", "dvdy")))
    dxx, dyy = g["VSG_STRAIN_XX"][points], g["VSG_STRAIN_YY"][points]
    u = np.where(member, fr.u[np.maximum(at, 0)], NA)
    v = np.where(member, fr.v[np.maximum(at, 0)], NA)
    oxx, oyy = (e[points] for e in dice_gauge(gx, gy, u, v, member, window))
    match = g.get("MATCH", np.zeros_like(gx)) == 0
    cxx, cyy = (e[points] for e in
                dice_gauge(gx, gy, g["DISPLACEMENT_X"], g["DISPLACEMENT_Y"], match, window))
    return {"points": int(points.sum()),
            "rms_diff_exx": rms(wxx - dxx), "rms_diff_eyy": rms(wyy - dyy),
            "max_diff_exx": max_abs(wxx - dxx), "max_diff_eyy": max_abs(wyy - dyy),
            "raw_rms_diff_exx": rms(rxx - dxx), "raw_rms_diff_eyy": rms(ryy - dyy),
            "gauge_rms_diff_exx": rms(oxx - dxx), "gauge_rms_diff_eyy": rms(oyy - dyy),
            "check_max_diff": max_abs(np.r_[cxx - dxx, cyy - dyy]),
            "dice_rms_exx": rms(dxx), "dice_rms_eyy": rms(dyy),
            "max_quadratic_xx": max_abs(wxx - win["dudx"][points]),
            "max_quadratic_yy": max_abs(wyy - win["dvdy"][points])}


def s12_strain_table(frames_idx, frames, gold, window):
    print(f"### Sample 12 strain against DICe's VSG strain ({window} px window)\n")
    print(f"DICe's VSG_STRAIN_XX, _YY are Green-Lagrange (its VSG post-processor: least-squares "
          f"plane of its valid displacements within {window / 2:g} px of the point, E = (H + H^T + "
          f"H^T H) / 2 of the plane's slopes; its GAMMA column is the match criterion, not a "
          f"shear). Ours, Green-Lagrange too: window = the mean of our warp gradients "
          f"(--warp-gradient) over our valid subsets at DICe's points within the same circle; raw "
          f"= the point's own subset. DICe's gauge on our u, v: DICe's plane fit applied to our "
          f"displacements at its points (the correlations' difference alone); check: the same fit "
          f"on DICe's own displacements against its VSG strain (the gauge reproduced). Points: "
          f"DICe's MATCH = 0 and ours valid. H^T H / 2 = the largest Green-Lagrange minus "
          f"small-strain term of our window strain.\n")
    print("| frame | points | RMS diff exx | RMS diff eyy | max diff exx | max diff eyy | raw: RMS "
          "diff exx, eyy | DICe's gauge on our u, v: RMS diff exx, eyy | check: max diff | DICe "
          "RMS exx, eyy | max H^T H / 2 xx, yy |")
    print("|---|---|---|---|---|---|---|---|---|---|---|")
    rows, notes = [], []
    for k, fr in zip(frames_idx, frames):
        g = gold[k]
        if "VSG_STRAIN_XX" not in g or "VSG_STRAIN_YY" not in g:
            notes.append(f"frame {k}: DICe's solution has no VSG_STRAIN_XX/_YY columns")
            continue
        if not np.isfinite(fr.grad["dudx"]).any():
            notes.append(f"frame {k}: no dudx_warp in our CSV (correlate --warp-gradient?)")
            continue
        r = {"frame": k, **s12_strain(fr, g, window)}
        rows.append(r)
        cells = [r["rms_diff_exx"], r["rms_diff_eyy"], r["max_diff_exx"], r["max_diff_eyy"],
                 (r["raw_rms_diff_exx"], r["raw_rms_diff_eyy"]),
                 (r["gauge_rms_diff_exx"], r["gauge_rms_diff_eyy"]), r["check_max_diff"],
                 (r["dice_rms_exx"], r["dice_rms_eyy"]),
                 (r["max_quadratic_xx"], r["max_quadratic_yy"])]
        print(f"| {k} | {r['points']} | " + " | ".join(
            ", ".join(sci(x) for x in c) if isinstance(c, tuple) else sci(c) for c in cells) + " |")
    print()
    notes_block(notes)
    return rows, not notes


# ---------------------------------------------------------------- real sand

def local_fit_residuals(fr, values, sigmas, cache):
    """Leave-one-out quadratic fit over the 5x5 grid window: (residual, normalised residual z,
    1 + h) per point where at least 12 valid neighbours exist; NaN elsewhere."""
    xs, ys = np.unique(fr.x), np.unique(fr.y)
    nx, ny = xs.size, ys.size
    if nx * ny != fr.x.size:
        raise Unmeasurable("the results are not one rectangular grid")
    col = np.searchsorted(xs, fr.x)
    row = np.searchsorted(ys, fr.y)
    grid = np.full((ny, nx), -1, int)
    grid[row, col] = np.arange(fr.x.size)
    n = fr.x.size
    res, z, lev = np.full(n, NA), np.full(n, NA), np.full(n, NA)
    for i in np.flatnonzero(fr.valid):
        r, c = row[i], col[i]
        nb, dxy = [], []
        for dr in range(-2, 3):
            for dc in range(-2, 3):
                if (dr or dc) and 0 <= r + dr < ny and 0 <= c + dc < nx:
                    j = grid[r + dr, c + dc]
                    if fr.valid[j]:
                        nb.append(j)
                        dxy.append((dc, dr))
        if len(nb) < 12:
            continue
        key = tuple(dxy)
        if key not in cache:  # the weights depend on which neighbours are valid only
            d = np.array(dxy, float)
            a = np.column_stack([np.ones(len(nb)), d[:, 0], d[:, 1], d[:, 0] ** 2,
                                 d[:, 0] * d[:, 1], d[:, 1] ** 2])
            try:
                cache[key] = np.linalg.solve(a.T @ a, a.T)[0]  # prediction at the centre = w . values
            except np.linalg.LinAlgError:
                cache[key] = None
        w = cache[key]
        if w is None:
            continue
        nb = np.array(nb)
        res[i] = values[i] - w @ values[nb]
        lev[i] = 1 + w @ w
        z[i] = res[i] / math.sqrt(sigmas[i] ** 2 + (w * w) @ (sigmas[nb] ** 2))
    return res, z, lev


def scatter_stats(fr, values, sigmas):
    res, z, lev = local_fit_residuals(fr, values, sigmas, {})
    ok = np.isfinite(z)
    if ok.sum() < 10:
        return {"points": int(ok.sum()), "ratio": NA, "ratio_mad": NA, "scatter": NA,
                "rms_sigma": NA, "outliers_percent": NA}
    zz = z[ok]
    mad = 1.4826 * float(np.median(np.abs(zz - np.median(zz))))
    inl = np.abs(zz) <= 5 * mad
    rr, ll = res[ok][inl], lev[ok][inl]
    return {"points": int(inl.sum()), "ratio": rms(zz[inl]), "ratio_mad": mad,
            "scatter": math.sqrt(float(np.mean(rr * rr / ll))), "rms_sigma": rms(sigmas[ok][inl]),
            "outliers_percent": 100.0 * (1 - inl.mean())}


def real_sand(ctx):
    folder = need_folder(os.path.join(ctx.data, "real-sand", "test48"), "real sand")
    names = sorted((n for n in os.listdir(folder) if re.fullmatch(r"IMG_\d+\.jpe?g", n, re.I)),
                   key=lambda n: int(re.search(r"\d+", n).group()))
    if len(names) < 2:
        raise Unmeasurable(f"real sand: fewer than 2 IMG_NN.jpg in {folder}")
    subset, step = ctx.args.sand_subset, ctx.args.sand_step
    roi = None if ctx.args.sand_roi == "full" else ctx.args.sand_roi
    flags = ["--mode", "sequence", "--subset", str(subset), "--step", str(step)]
    if roi:
        flags += ["--roi", roi]
    print(f"## Real sand test48 (sequence against {names[0]}, subset {subset}, step {step}"
          f"{', ROI ' + roi if roi else ', whole image'})\n")
    if roi == SAND_ROI:
        print("ROI: the sand below its surface (y 1280-1340 px in these frames); above it lies the "
              "tank's back wall behind the glass, with glare (`--sand-roi full`: the whole "
              "image).\n")
    print("No truth: scatter/sigma = rms of the residual from a quadratic fit of the 5x5 grid "
          "neighbours, normalised by its sd under the reported sigmas (1 = sigma right; "
          "|z| > 5 robust sd dropped, their share in `out`; 1.4826 MAD in brackets). scatter = "
          "the noise sd the residuals imply. Only valid subsets enter.\n")
    if step < subset:
        print(f"warning: step {step} < subset {subset}: neighbouring subsets overlap and share "
              f"noise, so the scatter is underestimated.\n")
    print("| frame | valid | invalid | median \\|d\\| [px] | scatter u, v [px] | rms sigma u, v [px] | "
          "scatter/sigma u | scatter/sigma v | out |")
    print("|---|---|---|---|---|---|---|---|---|")
    notes, rows_out, ok = [], [], True
    paths = [os.path.join(folder, n) for n in names]
    try:
        frames, seconds = ctx.run.correlate("sand", ["--reference", paths[0], "--deformed", *paths[1:]],
                                            flags, len(paths) - 1)
    except Unmeasurable as e:
        print("| n/a | n/a | n/a | n/a | n/a | n/a | n/a | n/a | n/a |\n")
        notes_block([str(e)])
        return {"error": str(e), "notes": [str(e)]}, False
    for name, fr in zip(names[1:], frames):
        try:
            su = scatter_stats(fr, fr.u, fr.su)
            sv = scatter_stats(fr, fr.v, fr.sv)
        except Unmeasurable as e:
            notes.append(f"{name}: scatter n/a: {e}")
            su = sv = {"ratio": NA, "ratio_mad": NA, "scatter": NA, "rms_sigma": NA,
                       "outliers_percent": NA, "points": 0}
        if math.isnan(su["ratio"]):
            notes.append(f"{name}: scatter n/a: fewer than 10 valid subsets with 12 valid neighbours")
        if not fr.valid.any():
            ok = False
        med = float(np.median(np.hypot(fr.u, fr.v)[fr.valid])) if fr.valid.any() else NA
        r = {"frame": name, "valid_percent": fr.valid_percent, "invalid": fr.invalid_summary(),
             "median_displacement": med, "u": su, "v": sv}
        rows_out.append(r)
        print(f"| {name} | {pct(r['valid_percent'])} | {r['invalid']} | {fmt(med, 2)} | "
              f"{fmt(su['scatter'])}, {fmt(sv['scatter'])} | {fmt(su['rms_sigma'])}, "
              f"{fmt(sv['rms_sigma'])} | {fmt(su['ratio'], 2)} ({fmt(su['ratio_mad'], 2)}) | "
              f"{fmt(sv['ratio'], 2)} ({fmt(sv['ratio_mad'], 2)}) | "
              f"{fmt(su['outliers_percent'], 1)}, {fmt(sv['outliers_percent'], 1)} % |")
    valid = [r["valid_percent"] for r in rows_out]
    print(f"\nlowest valid {pct(min(valid))}; {seconds:.1f} s\n")
    notes_block(notes)
    return {"subset": subset, "step": step, "roi": roi, "rows": rows_out, "notes": notes,
            "min_valid_percent": min(valid), "seconds": seconds}, ok


# ---------------------------------------------------------------- real static sand

def surface_residual(fr, values):
    """values minus a quadratic surface in (x, y) fitted to the valid subsets (NaN elsewhere)."""
    m = fr.valid
    if m.sum() < 12:
        raise Unmeasurable(f"{fr.label}: fewer than 12 valid subsets for the surface fit")
    x, y = fr.x / 1000.0, fr.y / 1000.0
    a = np.column_stack([np.ones_like(x), x, y, x * x, x * y, y * y])
    coef = np.linalg.lstsq(a[m], values[m], rcond=None)[0]
    res = np.full(values.size, NA)
    res[m] = values[m] - a[m] @ coef
    return res


def sigma_check(res, sigma):
    """rms(sigma) / sd(res) over all finite points and per quartile of sigma, with |res| > 5
    robust sd dropped."""
    ok = np.isfinite(res) & np.isfinite(sigma)
    r, s = res[ok], sigma[ok]
    mad = 1.4826 * float(np.median(np.abs(r - np.median(r))))
    keep = np.abs(r - np.median(r)) <= 5 * mad
    r, s = r[keep], s[keep]
    out = {"points": int(keep.sum()), "outliers_percent": 100.0 * (1 - keep.mean()),
           "scatter": sd(r), "rms_sigma": rms(s), "median_sigma": float(np.median(s))}
    out["ratio"] = ratio(out["rms_sigma"], out["scatter"])
    out["median_ratio"] = ratio(out["median_sigma"], out["scatter"])
    edges = np.quantile(s, [0, 0.25, 0.5, 0.75, 1])
    quartiles = []
    for q in range(4):
        b = (s >= edges[q]) & ((s < edges[q + 1]) if q < 3 else (s <= edges[q + 1]))
        quartiles.append(ratio(rms(s[b]), sd(r[b])) if b.sum() >= 10 else NA)
    out["quartile_ratios"] = quartiles
    out["ratio_min"] = min([out["ratio"]] + quartiles)
    out["ratio_max"] = max([out["ratio"]] + quartiles)
    return out


def real_static(ctx):
    folder = need_folder(os.path.join(ctx.data, "real-sand", "static"), "real static sand")
    names = sorted((n for n in os.listdir(folder) if re.fullmatch(r"IMG_\d+\.jpe?g", n, re.I)),
                   key=lambda n: int(re.search(r"\d+", n).group()))
    if len(names) < 2:
        raise Unmeasurable(f"real static sand: fewer than 2 IMG_N.jpg in {folder}")
    subset, step = ctx.args.sand_subset, ctx.args.sand_step
    roi = None if ctx.args.sand_roi == "full" else ctx.args.sand_roi
    flags = ["--mode", "pairs", "--subset", str(subset), "--step", str(step)]
    if roi:
        flags += ["--roi", roi]
    print(f"## Real static sand ({names[0]} against each of {', '.join(names[1:])}, pairs, subset "
          f"{subset}, step {step}{', ROI ' + roi if roi else ', whole image'})\n")
    print("Residual: each component less a quadratic surface fitted to the pair's valid subsets; "
          "sigma/scatter = rms(reported sigma) / sd(residual) over the same subsets (1 = sigma "
          "right), then within each quartile of the reported sigma; `median` = median sigma / sd "
          "of all (not a calibration figure: the large sigmas dominate the sd).\n")
    print("| pair | valid | scatter u, v [px] | rms sigma u, v [px] | sigma/scatter u | "
          "sigma/scatter v | quartiles u | quartiles v | median u, v | out |")
    print("|---|---|---|---|---|---|---|---|---|---|")
    paths = [os.path.join(folder, n) for n in names]
    try:
        frames, seconds = ctx.run.correlate("static", ["--reference", paths[0], "--deformed", *paths[1:]],
                                            flags, len(paths) - 1)
    except Unmeasurable as e:
        print("| n/a | n/a | n/a | n/a | n/a | n/a | n/a | n/a | n/a | n/a |\n")
        notes_block([str(e)])
        return {"error": str(e), "notes": [str(e)]}, False
    rows_out, notes, ok = [], [], True
    for name, fr in zip(names[1:], frames):
        try:
            su = sigma_check(surface_residual(fr, fr.u), fr.su)
            sv = sigma_check(surface_residual(fr, fr.v), fr.sv)
        except Unmeasurable as e:
            notes.append(str(e))
            ok = False
            continue
        r = {"pair": f"{names[0]}-{name}", "frame": name, "valid_percent": fr.valid_percent,
             "u": su, "v": sv}
        rows_out.append(r)
        qs = lambda c: " ".join(fmt(x, 2) for x in c["quartile_ratios"])
        print(f"| {r['pair']} | {pct(r['valid_percent'])} | {fmt(su['scatter'])}, {fmt(sv['scatter'])} | "
              f"{fmt(su['rms_sigma'])}, {fmt(sv['rms_sigma'])} | {fmt(su['ratio'], 2)} | "
              f"{fmt(sv['ratio'], 2)} | {qs(su)} | {qs(sv)} | {fmt(su['median_ratio'], 2)}, "
              f"{fmt(sv['median_ratio'], 2)} | {fmt(su['outliers_percent'], 1)}, "
              f"{fmt(sv['outliers_percent'], 1)} % |")
    print(f"\n{seconds:.1f} s\n")
    notes_block(notes)
    return {"subset": subset, "step": step, "roi": roi, "rows": rows_out, "notes": notes,
            "seconds": seconds}, ok


# ---------------------------------------------------------------- synthetic noise

def synthetic_images(size, shifts, noise, seed):
    """Reference and shifted 8-bit images of one band-limited speckle: I_k(x) = I(x - shift_k)
    exactly (Fourier shift of a periodic pattern), each with its own Gaussian noise."""
    rng = np.random.default_rng(seed)
    f = np.fft.fftfreq(size)
    fx, fy = np.meshgrid(f, f)
    blob_px = 1.5
    spectrum = np.fft.fft2(rng.standard_normal((size, size))) * np.exp(
        -2 * math.pi ** 2 * blob_px ** 2 * (fx ** 2 + fy ** 2))
    base = np.real(np.fft.ifft2(spectrum))
    scale = 30.0 / base.std()
    images = []
    for u, v in [(0.0, 0.0)] + list(shifts):
        img = np.real(np.fft.ifft2(spectrum * np.exp(-2j * math.pi * (fx * u + fy * v))))
        img = 128 + scale * img + rng.normal(0, noise, img.shape)
        images.append(np.clip(np.rint(img), 0, 255).astype(np.uint8))
    return images


def synthetic(ctx):
    size, subset, step = 512, 25, 25
    shifts = [(0.3, 0.2), (0.5, -0.5), (0.85, 0.4)]
    levels = (2.0,) if ctx.quick else (2.0, 5.0)
    print(f"## Synthetic noise ({size}x{size}, speckle sd 30 grey levels, blob 1.5 px, exact "
          f"Fourier shifts; pairs, subset {subset}, step {step})\n")
    print("| noise [grey] | shift u, v [px] | valid | bias u, v [px] | sd u, v [px] | "
          "rms sigma u, v [px] | sigma/sd u | sigma/sd v |")
    print("|---|---|---|---|---|---|---|---|")
    notes, rows_out, ok = [], [], True
    for level in levels:
        images = synthetic_images(size, shifts, level, seed=21)
        paths = []
        for k, img in enumerate(images):
            p = os.path.join(ctx.work, f"synth_n{level:g}_{k}.tif")
            tiff_lite.write_tiff(p, tiff_lite.Image(size, size, 8, img.tobytes()))
            paths.append(p)
        try:
            frames, _ = ctx.run.correlate(f"synth_n{level:g}", ["--reference", paths[0], "--deformed", *paths[1:]],
                                          ["--mode", "pairs", "--subset", str(subset), "--step", str(step)],
                                          len(shifts))
        except Unmeasurable as e:
            print(f"| {level:g} | n/a | n/a | n/a | n/a | n/a | n/a | n/a |")
            notes.append(str(e))
            ok = False
            continue
        for (u, v), fr in zip(shifts, frames):
            m = fr.valid
            eu, ev = fr.u[m] - u, fr.v[m] - v
            r = {"noise": level, "shift": [u, v], "valid_percent": fr.valid_percent,
                 "bias_u": mean(eu), "bias_v": mean(ev), "sd_u": sd(eu), "sd_v": sd(ev),
                 "rms_sigma_u": rms(fr.su[m]), "rms_sigma_v": rms(fr.sv[m])}
            r["ratio_u"] = ratio(r["rms_sigma_u"], r["sd_u"])
            r["ratio_v"] = ratio(r["rms_sigma_v"], r["sd_v"])
            if m.sum() < 2:
                notes.append(f"noise {level:g}, shift {u}, {v}: fewer than 2 valid subsets ({fr.invalid_summary()})")
                ok = False
            rows_out.append(r)
            print(f"| {level:g} | {u:.2f}, {v:.2f} | {pct(r['valid_percent'])} | {fmt(r['bias_u'])}, "
                  f"{fmt(r['bias_v'])} | {fmt(r['sd_u'])}, {fmt(r['sd_v'])} | "
                  f"{fmt(r['rms_sigma_u'])}, {fmt(r['rms_sigma_v'])} | {fmt(r['ratio_u'], 2)} | "
                  f"{fmt(r['ratio_v'], 2)} |")
    print()
    notes_block(notes)
    return {"size": size, "subset": subset, "step": step, "rows": rows_out, "notes": notes}, ok


# ---------------------------------------------------------------- targets

def targets(results):
    """(name, measured, required, pass) of the issue's targets that the results cover."""
    lo, hi = TARGET_SIGMA_RATIO
    out = []

    def add(name, value, required, good):
        out.append((name, value, required, None if math.isnan(value) else bool(good(value))))

    s3 = results.get("s3", {}).get("interpolators", {})
    for interp, r in s3.items():
        if "max_abs_bias_px" in r:
            add(f"s3_{interp}_max_abs_bias_px", r["max_abs_bias_px"], f"<= {TARGET_S3_MAX_BIAS_PX}",
                lambda x: x <= TARGET_S3_MAX_BIAS_PX)
            for key in ("sigma_ratio_min", "sigma_ratio_max"):
                add(f"s3_{interp}_{key}", r[key], f"in [{lo}, {hi}]", lambda x: lo <= x <= hi)
    for r in results.get("s14", {}).get("rows", []):
        for comp in ("u", "v"):
            add(f"s14_L{r['level']}_sigma_over_error_{comp}", r[f"ratio_{comp}"], f"in [{lo}, {hi}]",
                lambda x: lo <= x <= hi)
    for r in results.get("sand", {}).get("rows", []):
        add(f"sand_{r['frame']}_valid_percent", r["valid_percent"], f">= {TARGET_SAND_VALID_PERCENT}",
            lambda x: x >= TARGET_SAND_VALID_PERCENT)
    for r in results.get("static", {}).get("rows", []):
        for comp in ("u", "v"):
            for key in ("ratio_min", "ratio_max"):
                add(f"static_{r['frame']}_sigma_over_scatter_{comp}_{key[6:]}", r[comp][key],
                    f"in [{lo}, {hi}]", lambda x: lo <= x <= hi)
    for r in results.get("synth", {}).get("rows", []):
        for comp in ("u", "v"):
            add(f"synth_noise{r['noise']:g}_shift{r['shift'][0]:g}_sigma_over_sd_{comp}",
                r[f"ratio_{comp}"], f"in [{lo}, {hi}]", lambda x: lo <= x <= hi)
    return out


# ---------------------------------------------------------------- main

class Context:
    pass


def main():
    argv = sys.argv[1:]
    extra = []
    if "--" in argv:
        i = argv.index("--")
        argv, extra = argv[:i], argv[i + 1:]
    p = argparse.ArgumentParser(description=__doc__.split("\n")[0],
                                formatter_class=argparse.RawDescriptionHelpFormatter, epilog=__doc__)
    p.add_argument("--binary", default=os.path.join(ROOT, "build", "release", "src", "cli", "impactdic"),
                   help="impactdic binary (default build/release/src/cli/impactdic)")
    p.add_argument("--data", default=DEFAULT_DATA, help=f"shared benchmark data (default {DEFAULT_DATA})")
    p.add_argument("--only", default=",".join(SECTIONS), help="sections, comma separated: " + ",".join(SECTIONS))
    p.add_argument("--quick", action="store_true", help="the fast subset of the targets test")
    p.add_argument("--check", action="store_true", help="print the issue's targets, PASS/FAIL")
    p.add_argument("--json", help="also write every figure to this JSON file (n/a as null)")
    p.add_argument("--threads", type=int, default=0, help="correlate --threads (0: all cores)")
    p.add_argument("--work", help="folder for the CSVs and synthetic images (default: temporary)")
    p.add_argument("--s3-subset", type=int, default=25)
    p.add_argument("--s3-step", type=int, default=10)
    p.add_argument("--s14-subset", type=int, default=25)
    p.add_argument("--s14-step", type=int, default=5)
    p.add_argument("--s14-roi", help="X0,Y0,X1,Y1 (default: whole image)")
    p.add_argument("--sand-subset", type=int, default=25)
    p.add_argument("--sand-step", type=int, default=50)
    p.add_argument("--sand-roi", default=SAND_ROI,
                   help=f"X0,Y0,X1,Y1 or full (default {SAND_ROI}: the sand below its surface)")
    args = p.parse_args(argv)
    only = [s.strip() for s in args.only.split(",") if s.strip()]
    bad = [s for s in only if s not in SECTIONS]
    if bad:
        p.error(f"--only: unknown section(s) {bad}; known: {', '.join(SECTIONS)}")
    binary = os.path.abspath(args.binary)
    if not os.access(binary, os.X_OK):
        print(f"dic_challenge: error: --binary: {binary} is not an executable (build it: cmake "
              f"--build --preset release --target impactdic)", file=sys.stderr)
        return 2
    ctx = Context()
    ctx.args, ctx.quick, ctx.data = args, args.quick, os.path.abspath(args.data)
    ctx.work = args.work or tempfile.mkdtemp(prefix="impactdic_dic_challenge_")
    os.makedirs(ctx.work, exist_ok=True)
    ctx.run = Runner(binary, extra, args.threads, ctx.work)
    version = subprocess.run([binary, "version"], capture_output=True, text=True).stdout.strip()
    print(f"# impactdic on the public benchmark images\n\nbinary {binary} ({version}); data "
          f"{ctx.data}; extra correlate flags: {' '.join(extra) if extra else '(none: defaults)'}"
          f"{'; --quick' if ctx.quick else ''}; work folder {ctx.work}\n")
    results, all_ok = {"binary": binary, "version": version, "extra_flags": extra,
                       "quick": ctx.quick, "data": ctx.data}, True
    runners = {"s3": sample3, "s14": sample14, "s12": sample12, "sand": real_sand, "static": real_static,
               "synth": synthetic}
    for name in only:
        try:
            results[name], ok = runners[name](ctx)
        except (Unmeasurable, tiff_lite.TiffError, OSError) as e:
            print(f"## {name}: n/a\n\nnote: {e}\n")
            results[name], ok = {"error": str(e)}, False
        all_ok = all_ok and ok
    if args.check:
        print("## Targets\n")
        print("| target | measured | required | result |")
        print("|---|---|---|---|")
        for name, value, required, good in targets(results):
            print(f"| {name} | {fmt(value)} | {required} | "
                  f"{'n/a' if good is None else 'PASS' if good else 'FAIL'} |")
        print()
        results["targets"] = [{"target": n, "measured": v, "required": r, "pass": g}
                              for n, v, r, g in targets(results)]
    for w in ctx.run.warnings:
        print("warning: " + w + "\n")
    print("## Commands\n")
    for name, cmd, seconds in ctx.run.commands:
        print(f"- {name} ({seconds:.1f} s): `{cmd}`")
    print()
    if args.json:
        with open(args.json, "w") as f:
            json.dump(jsonable(results), f, indent=1)
    return 0 if all_ok else 1


if __name__ == "__main__":
    sys.exit(main())
