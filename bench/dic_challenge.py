#!/usr/bin/env python3
"""DIC Challenge 1.0 (2D) Samples 3 and 14 through `impactdic correlate` (issue 13, items 1-2).

    scripts/fetch_dic_challenge.sh                 # downloads + unpacks into DATA (see there)
    bench/dic_challenge.py [DATA]                  # prints the two tables below

DATA (default: ${XDG_CACHE_HOME:-~/.cache}/impactdic/dic_challenge, the fetch script's default)
holds Sample3/ and Sample14/ as unpacked from the challenge's archives; files are found by name
anywhere below those folders:
  Sample 3:  "Sample3 Reference.tif" and "Sample3-NNN X<u> Y<v> N2 C0 R0.tif" (rigid shifts,
             the imposed u, v in px read from the name: X0.30 Y0.30 -> u = v = +0.30 px).
  Sample 14: "Sample14 Reference.tif" and "Sample14 L<k> Amp<A>[b].tif" (also "Sample 14 ...").

Sample 3 (per interpolator, bicubic and biquintic; subset 25, step 10, --mode pairs, no
uncertainty limit): one row per shifted image, each correlated against the reference:
  shift u, v | bias u, v (mean error) | sd u, v | noise limit | mean reported sigma u, v | n
The noise limit is the rms over the subsets of sqrt(2) sigma_n / sqrt(sum over the subset of
(dI/dx)^2) (the sd of u that image noise alone gives, noise in both images; the v limit uses
dI/dy and is printed as the second number), with dI/dx the central difference of the reference and
sigma_n = sd(reference - zero-shift image) / sqrt(2) over the whole image (the X0.00 Y0.00 image
shows the same pattern with its own noise). Without a zero-shift image, or when the TIFF cannot
be decoded, the column is nan and the reason is printed.

Sample 14 (subset 25, step 5, --mode pairs, --max-uncertainty none; bicubic unless --s14-interp):
one row per deformed image: converged / all subsets, RMS error of u and v over ALL converged
subsets, the fraction that would be `uncertain` at correlate's default limit (read from
`correlate --help`), and the rms of the reported sigma_u, sigma_v.
Truth: Sample 14's u is not one sinusoid but a chirp of amplitude 0.1 px along x (zero up to
x = 100 px, the frequency rising to the right; L1 lowest, L5 highest), v = 0. The commanded u per
pixel column for L1, L3 and L5 is the table DATA/Sample14_command.csv (x, u_L1, exx_L1, u_L3,
exx_L3, u_L5, exx_L5; the copy in Sandia's DICe repository, fetched by the fetch script;
--s14-truth FILE to give another), interpolated linearly at the subset centre X. Levels without a
column (L2, L4) get nan with a note; so do all without the table.

Images of unequal size (Sample 14's deformed images may be larger than its reference) are cropped
to their common top-left size into the work folder first (pure-Python TIFF, bench/tiff_lite.py).

Exit status: 0 tables printed; 2 bad arguments or missing/unreadable data (message names it);
1 `impactdic correlate` failed (its output is printed).
"""

import argparse
import csv
import math
import os
import re
import subprocess
import sys
import tempfile

sys.dont_write_bytecode = True  # no __pycache__ in the source tree
sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))
import tiff_lite  # noqa: E402

# The name of `impactdic correlate`'s Gaussian pre-filter option (issue 13 item 1; docs/dic.md,
# "Sub-pixel bias"): --prefilter SIGMA passes `--gaussian SIGMA` (kernel 5).
CORRELATE_PREFILTER_OPTION = "--gaussian"

DEFAULT_DATA = os.path.join(os.environ.get("XDG_CACHE_HOME") or os.path.expanduser("~/.cache"),
                            "impactdic", "dic_challenge")
S3_REFERENCE = re.compile(r"^sample\s*3 reference\.tiff?$", re.I)
S3_DEFORMED = re.compile(r"^sample\s*3-(\d+) x(-?\d+(?:\.\d+)?) y(-?\d+(?:\.\d+)?)\b.*\.tiff?$", re.I)
S14_REFERENCE = re.compile(r"^sample\s*14 reference\.tiff?$", re.I)
S14_DEFORMED = re.compile(r"^sample\s*14 l(\d+) amp(\d+(?:\.\d+)?)[a-z]?\.tiff?$", re.I)


class BenchError(Exception):
    def __init__(self, message, status=2):
        super().__init__(message)
        self.status = status


def find(folder, pattern):
    hits = []
    for root, _, files in os.walk(folder):
        for name in files:
            m = pattern.match(name)
            if m:
                hits.append((os.path.join(root, name), m))
    return sorted(hits, key=lambda h: h[0])


def one_reference(folder, pattern, what):
    refs = find(folder, pattern)
    if len(refs) != 1:
        raise BenchError(f"{what}: expected one reference image matching '{pattern.pattern}' under "
                         f"{folder}, found {len(refs)}" + (f": {[r[0] for r in refs]}" if refs else ""))
    return refs[0][0]


def default_limit(binary):
    """correlate's default --max-uncertainty, from its --help (one definition: the library's)."""
    out = subprocess.run([binary, "correlate", "--help"], capture_output=True, text=True).stdout
    m = re.search(r"--max-uncertainty\s+TEXT=([0-9.eE+-]+)", out)
    if not m:
        raise BenchError(f"{binary} correlate --help does not show a --max-uncertainty default", 1)
    return float(m.group(1)), out


def correlate(binary, reference, deformed, out_csv, args, subset, step, interp):
    """One `correlate --mode pairs` of `deformed` (a list of paths) against `reference`: the
    command and the result rows of each deformed image, in order."""
    cmd = [binary, "-q", "correlate", "--reference", reference, "--deformed", *deformed,
           "--mode", "pairs", "--subset", str(subset), "--step", str(step), "--interp", interp,
           "--max-uncertainty", "none", "--threads", str(args.threads), "-o", out_csv]
    if args.prefilter is not None:
        cmd += [CORRELATE_PREFILTER_OPTION, str(args.prefilter)]
    proc = subprocess.run(cmd, capture_output=True, text=True)
    if proc.returncode != 0:
        raise BenchError(f"impactdic correlate failed (exit {proc.returncode}): "
                         f"{' '.join(quote(c) for c in cmd)}\n{proc.stdout}{proc.stderr}", 1)
    return cmd, read_results(out_csv, len(deformed))


def quote(s):
    return s if re.fullmatch(r"[\w./=:+-]+", s) else "'" + s.replace("'", "'\\''") + "'"


def read_results(path, count):
    """Rows of each of the `count` deformed images of a correlate CSV, in order. The `frame`
    column is the position (reference = 0) when the names are not one numbered series, as the
    challenge's are not (docs/dic.md); with one image, its rows are the last frame's."""
    with open(path, newline="") as f:
        rows = list(csv.DictReader(f))
    for col in ("frame", "x_px", "y_px", "u_px", "v_px", "status", "sigma_u_px", "sigma_v_px"):
        if rows and col not in rows[0]:
            raise BenchError(f"{path}: no column '{col}' (correlate's CSV contract changed?)", 1)
    if not rows:
        raise BenchError(f"{path}: no results", 1)
    if count == 1:
        last = rows[-1]["frame"]
        return [[r for r in rows if r["frame"] == last]]
    frames = sorted({int(r["frame"]) for r in rows} - {0})
    if frames != list(range(1, count + 1)):
        raise BenchError(f"{path}: frames {frames[:5]}... are not the positions 1..{count} of the "
                         f"deformed images; cannot tell which result is which image", 1)
    return [[r for r in rows if int(r["frame"]) == k] for k in frames]


def mean(xs):
    return sum(xs) / len(xs) if xs else math.nan


def sd(xs):
    if len(xs) < 2:
        return math.nan
    m = mean(xs)
    return math.sqrt(sum((x - m) ** 2 for x in xs) / (len(xs) - 1))


def rms(xs):
    return math.sqrt(sum(x * x for x in xs) / len(xs)) if xs else math.nan


def converged(rows):
    return [r for r in rows if r["status"] == "converged"]


def fmt(x, digits=4):
    return "nan" if x is None or math.isnan(x) else f"{x:.{digits}f}"


# ---------------------------------------------------------------- noise limit (Sample 3)

class GradientSums:
    """Summed-area tables of (dI/dx)^2 and (dI/dy)^2 (central differences) of an image."""

    def __init__(self, img):
        w, h, p = img.width, img.height, img.pixels
        self.w, self.h = w, h
        self.sx = [[0.0] * (w + 1) for _ in range(h + 1)]
        self.sy = [[0.0] * (w + 1) for _ in range(h + 1)]
        for y in range(h):
            row, up, down = y * w, max(y - 1, 0) * w, min(y + 1, h - 1) * w
            ax = ay = 0.0
            sx0, sx1, sy0, sy1 = self.sx[y], self.sx[y + 1], self.sy[y], self.sy[y + 1]
            for x in range(w):
                gx = (p[row + min(x + 1, w - 1)] - p[row + max(x - 1, 0)]) * 0.5
                gy = (p[down + x] - p[up + x]) * 0.5
                ax += gx * gx
                ay += gy * gy
                sx1[x + 1] = sx0[x + 1] + ax
                sy1[x + 1] = sy0[x + 1] + ay

    def box(self, table, x0, y0, x1, y1):  # inclusive pixel box, clipped
        x0, y0 = max(x0, 0), max(y0, 0)
        x1, y1 = min(x1, self.w - 1), min(y1, self.h - 1)
        t = table
        return t[y1 + 1][x1 + 1] - t[y0][x1 + 1] - t[y1 + 1][x0] + t[y0][x0]


def noise_sigma(reference, zero_shift):
    a, b = tiff_lite.read_tiff(reference), tiff_lite.read_tiff(zero_shift)
    if (a.width, a.height) != (b.width, b.height):
        raise tiff_lite.TiffError(f"{zero_shift}: size differs from the reference")
    return sd([p - q for p, q in zip(a.pixels, b.pixels)]) / math.sqrt(2), a


def noise_limits(grad, rows, subset, sigma_n):
    """rms over the subsets of the predicted sd of u and of v."""
    half = subset // 2
    vu, vv = [], []
    for r in rows:
        x, y = int(round(float(r["x_px"]))), int(round(float(r["y_px"])))
        sxx = grad.box(grad.sx, x - half, y - half, x + half, y + half)
        syy = grad.box(grad.sy, x - half, y - half, x + half, y + half)
        if sxx > 0 and syy > 0:
            vu.append(2 * sigma_n ** 2 / sxx)
            vv.append(2 * sigma_n ** 2 / syy)
    return (math.sqrt(mean(vu)), math.sqrt(mean(vv))) if vu else (math.nan, math.nan)


def sample3(args, binary, work):
    folder = os.path.join(args.data, "Sample3") if not args.sample3 else args.sample3
    if not os.path.isdir(folder):
        raise BenchError(f"Sample 3: no folder {folder} (run scripts/fetch_dic_challenge.sh, or "
                         f"give --sample3 DIR)")
    reference = one_reference(folder, S3_REFERENCE, "Sample 3")
    deformed = [(path, float(m.group(2)), float(m.group(3))) for path, m in find(folder, S3_DEFORMED)]
    if not deformed:
        raise BenchError(f"Sample 3: no shifted images 'Sample3-NNN X.. Y.. ....tif' under {folder}")
    print(f"## DIC Challenge 1.0 Sample 3: {len(deformed)} shifted images against "
          f"'{os.path.basename(reference)}' ({folder})\n")
    limit_note, grad, sigma_n = "", None, math.nan
    zero = [d for d in deformed if d[1] == 0 and d[2] == 0]
    try:
        if not zero:
            raise tiff_lite.TiffError("no zero-shift image (X0.00 Y0.00) to estimate the noise from")
        sigma_n, ref_img = noise_sigma(reference, zero[0][0])
        grad = GradientSums(ref_img)
        limit_note = (f"noise sigma_n = {sigma_n:.3f} grey levels = sd(reference - "
                      f"'{os.path.basename(zero[0][0])}') / sqrt(2)")
    except (tiff_lite.TiffError, OSError, KeyError) as e:
        limit_note = f"noise limit not computed (nan): {e}"
    print(limit_note + "\n")
    for interp in ("bicubic", "biquintic"):
        print(f"### {interp}, subset {args.s3_subset}, step {args.s3_step}\n")
        print("| shift u, v [px] | bias u [px] | bias v [px] | sd u [px] | sd v [px] | "
              "noise limit u, v [px] | mean sigma u, v [px] | n |")
        print("|---|---|---|---|---|---|---|---|")
        max_bias, cmd, warnings = 0.0, None, []
        cmd, results = correlate(binary, reference, [d[0] for d in deformed],
                                 os.path.join(work, f"s3_{interp}.csv"), args, args.s3_subset,
                                 args.s3_step, interp)
        for (path, su, sv), rows in zip(deformed, results):
            ok = converged(rows)
            eu = [float(r["u_px"]) - su for r in ok]
            ev = [float(r["v_px"]) - sv for r in ok]
            lu, lv = noise_limits(grad, ok, args.s3_subset, sigma_n) if grad else (math.nan,) * 2
            bu, bv = mean(eu), mean(ev)
            max_bias = max(max_bias, abs(bu), abs(bv)) if ok else max_bias
            print(f"| {su:.2f}, {sv:.2f} | {fmt(bu)} | {fmt(bv)} | {fmt(sd(eu))} | {fmt(sd(ev))} | "
                  f"{fmt(lu)}, {fmt(lv)} | {fmt(mean([float(r['sigma_u_px']) for r in ok]))}, "
                  f"{fmt(mean([float(r['sigma_v_px']) for r in ok]))} | {len(ok)}/{len(rows)} |")
            if ok and (su or sv) and abs(mean([float(r['u_px']) for r in ok]) + su) < abs(bu):
                warnings.append(f"warning: {os.path.basename(path)}: the measured shift is closer "
                                f"to the opposite of the name's; the sign convention assumed here "
                                f"may be wrong")
        print(f"\nmax |bias| {interp}: {max_bias:.4f} px\n")
        for w in warnings:
            print(w)
        print("command: " + " ".join(quote(c) for c in cmd) + "\n")


# ---------------------------------------------------------------- Sample 14

def read_truth(path):
    """Commanded u of Sample 14 per level from a table x, u_L1, exx_L1, u_L3, exx_L3, u_L5,
    exx_L5 (one row per integer x of the reference, no header; exx in microstrain, unused):
    {level: [u at x = 0, 1, ...]}."""
    columns = {1: 1, 3: 3, 5: 5}
    table = {k: [] for k in columns}
    with open(path, newline="") as f:
        for n, row in enumerate(csv.reader(f), start=1):
            try:
                values = [float(c) for c in row]
            except ValueError:
                raise BenchError(f"--s14-truth {path}: line {n} is not numbers: {row[:3]}")
            if len(values) < 7 or int(values[0]) != n - 1:
                raise BenchError(f"--s14-truth {path}: line {n}: expected 7 columns x, u_L1, "
                                 f"exx_L1, u_L3, exx_L3, u_L5, exx_L5 with x = {n - 1}")
            for k, c in columns.items():
                table[k].append(values[c])
    if not table[1]:
        raise BenchError(f"--s14-truth {path}: empty")
    return table


def truth_at(column, x):
    """Linear interpolation of a per-pixel column at x (clamped to the table)."""
    x = min(max(x, 0.0), len(column) - 1.0)
    i = min(int(x), len(column) - 2)
    return column[i] + (x - i) * (column[i + 1] - column[i])


def same_size(reference, deformed, work):
    """Paths of the reference and deformed image with equal sizes (cropped copies if needed)."""
    rw, rh = tiff_lite.read_size(reference)
    dw, dh = tiff_lite.read_size(deformed)
    if (rw, rh) == (dw, dh):
        return reference, deformed, ""
    w, h = min(rw, dw), min(rh, dh)
    out = []
    for path, (pw, ph) in ((reference, (rw, rh)), (deformed, (dw, dh))):
        if (pw, ph) == (w, h):
            out.append(path)
            continue
        cropped = os.path.join(work, f"crop_{w}x{h}_{os.path.basename(path)}")
        tiff_lite.write_tiff(cropped, tiff_lite.crop(tiff_lite.read_tiff(path), w, h))
        out.append(cropped)
    note = f"sizes {rw}x{rh} (reference) and {dw}x{dh}: cropped to the common top-left {w}x{h}"
    return out[0], out[1], note


def sample14(args, binary, work, limit):
    folder = os.path.join(args.data, "Sample14") if not args.sample14 else args.sample14
    if not os.path.isdir(folder):
        raise BenchError(f"Sample 14: no folder {folder} (run scripts/fetch_dic_challenge.sh, or "
                         f"give --sample14 DIR)")
    reference = one_reference(folder, S14_REFERENCE, "Sample 14")
    deformed = [(path, int(m.group(1)), float(m.group(2))) for path, m in find(folder, S14_DEFORMED)]
    if not deformed:
        raise BenchError(f"Sample 14: no deformed images 'Sample14 L<k> Amp<A>.tif' under {folder}")
    truth_path = args.s14_truth or os.path.join(args.data, "Sample14_command.csv")
    truth = read_truth(truth_path) if os.path.isfile(truth_path) else {}
    print(f"## DIC Challenge 1.0 Sample 14: {len(deformed)} deformed images against "
          f"'{os.path.basename(reference)}' ({folder}); {args.s14_interp}, subset "
          f"{args.s14_subset}, step {args.s14_step}, --max-uncertainty none\n")
    print(f"Truth: the commanded u(X) of the image's level from {truth_path}"
          f"{'' if truth else ' (missing: no RMS error)'}, v = 0. `uncertain at default`: converged "
          f"subsets with sigma_u or sigma_v > {limit:g} px (correlate's default limit).\n")
    print("| image | converged / all | RMS err u [px] | RMS err v [px] | RMS err 2-D [px] | "
          "uncertain at default | rms sigma u, v [px] | truth |")
    print("|---|---|---|---|---|---|---|---|")
    cmd, notes = None, []
    for path, level, _ in deformed:
        name = os.path.basename(path)
        ref, dfm, note = same_size(reference, path, work)
        if note:
            notes.append(f"{name}: {note}")
        out = os.path.join(work, f"s14_{name}.csv")
        cmd, (rows,) = correlate(binary, ref, [dfm], out, args, args.s14_subset, args.s14_step,
                                 args.s14_interp)
        ok = converged(rows)
        vs = [float(r["v_px"]) for r in ok]
        su = [float(r["sigma_u_px"]) for r in ok]
        sv = [float(r["sigma_v_px"]) for r in ok]
        unc = sum(1 for p, q in zip(su, sv) if p > limit or q > limit)
        err_u, source = math.nan, "none"
        if level in truth and ok:
            eu = [float(r["u_px"]) - truth_at(truth[level], float(r["x_px"])) for r in ok]
            flipped = [float(r["u_px"]) + truth_at(truth[level], float(r["x_px"])) for r in ok]
            err_u, source = rms(eu), f"L{level} of {os.path.basename(truth_path)}"
            if rms(flipped) < 0.5 * err_u:
                notes.append(f"{name}: u matches the opposite of the commanded displacement; "
                             f"the sign convention assumed here may be wrong")
        elif truth:
            notes.append(f"{name}: no commanded displacement for level L{level} in {truth_path} "
                         f"(it has L1, L3, L5): RMS error nan")
        pct = f"{100.0 * unc / len(ok):.2f} %" if ok else "nan"
        print(f"| {name} | {len(ok)}/{len(rows)} | {fmt(err_u)} | {fmt(rms(vs))} | "
              f"{fmt(math.sqrt(err_u ** 2 + rms(vs) ** 2))} | {pct} | "
              f"{fmt(rms(su))}, {fmt(rms(sv))} | {source} |")
    print()
    for n in notes:
        print("note: " + n)
    print("command (per image): " + " ".join(quote(c) for c in cmd) + "\n")


def main():
    p = argparse.ArgumentParser(description=__doc__.split("\n")[0],
                                formatter_class=argparse.RawDescriptionHelpFormatter)
    p.add_argument("data", nargs="?", default=DEFAULT_DATA,
                   help=f"folder with Sample3/ and Sample14/ (default {DEFAULT_DATA})")
    here = os.path.dirname(os.path.abspath(__file__))
    p.add_argument("--binary", default=os.path.join(here, "..", "build", "release", "src", "cli",
                                                    "impactdic"), help="impactdic binary")
    p.add_argument("--sample3", help="Sample 3 folder (default DATA/Sample3)")
    p.add_argument("--sample14", help="Sample 14 folder (default DATA/Sample14)")
    p.add_argument("--only", choices=("3", "14"), help="run one sample only")
    p.add_argument("--threads", type=int, default=0, help="correlate --threads (0: all cores)")
    p.add_argument("--work", help="folder for the CSVs and cropped images (default: a temporary one)")
    p.add_argument("--s3-subset", type=int, default=25)
    p.add_argument("--s3-step", type=int, default=10)
    p.add_argument("--s14-subset", type=int, default=25)
    p.add_argument("--s14-step", type=int, default=5)
    p.add_argument("--s14-interp", default="bicubic", choices=("bicubic", "biquintic"))
    p.add_argument("--s14-truth", help="Sample 14 commanded displacement table (default "
                   "DATA/Sample14_command.csv, fetched by scripts/fetch_dic_challenge.sh)")
    p.add_argument("--prefilter", type=float, metavar="SIGMA",
                   help="pass correlate's Gaussian pre-filter (needs CORRELATE_PREFILTER_OPTION)")
    args = p.parse_args()
    try:
        if args.prefilter is not None and CORRELATE_PREFILTER_OPTION is None:
            raise BenchError("--prefilter: correlate has no pre-filter option known to this script "
                             "yet; set CORRELATE_PREFILTER_OPTION in bench/dic_challenge.py")
        binary = os.path.abspath(args.binary)
        if not os.access(binary, os.X_OK):
            raise BenchError(f"--binary: {binary} is not an executable (build it: cmake --build "
                             f"--preset release --target impactdic)")
        limit, help_text = default_limit(binary)
        if args.prefilter is not None and CORRELATE_PREFILTER_OPTION not in help_text:
            raise BenchError(f"--prefilter: {binary} correlate has no {CORRELATE_PREFILTER_OPTION}")
        work = args.work or tempfile.mkdtemp(prefix="impactdic_dic_challenge_")
        os.makedirs(work, exist_ok=True)
        print(f"binary {binary}; results in {work}\n")
        if args.only in (None, "3"):
            sample3(args, binary, work)
        if args.only in (None, "14"):
            sample14(args, binary, work, limit)
    except BenchError as e:
        print(f"dic_challenge: error: {e}", file=sys.stderr)
        return e.status
    except (tiff_lite.TiffError, OSError) as e:
        print(f"dic_challenge: error: {e}", file=sys.stderr)
        return 2
    return 0


if __name__ == "__main__":
    sys.exit(main())
