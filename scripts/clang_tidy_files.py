#!/usr/bin/env python3
"""Runs clang-tidy over the src/ files of a configured build, each in its own process, JOBS at once,
and remembers which files were clean (scripts/clang_tidy.sh runs it; see there for the options).

A file is linted again unless its clean result is remembered under the same fingerprint: the
sha256 of clang-tidy's version, .clang-tidy, the file's compile command and its preprocessed text
(every header it reads, the project's and the system's), with the checkout's folder written as
@ROOT@ so that another clone of the same tree shares the entries. Only clean results are kept: a
file with a finding is linted, and reported, every time.

Usage: clang_tidy_files.py BUILD_DIR JOBS CACHE_DIR|off
Prints the findings; exits 1 when there are any, 2 when a file cannot be preprocessed.
"""

import concurrent.futures
import hashlib
import json
import os
import pathlib
import shlex
import subprocess
import sys

ROOT = pathlib.Path(__file__).resolve().parent.parent


def compile_commands(build_dir):
    """The src/*.cc entries of BUILD_DIR/compile_commands.json, one per file, sorted."""
    with open(build_dir / "compile_commands.json", encoding="utf-8") as f:
        entries = json.load(f)
    src = ROOT / "src"
    files = {}
    for e in entries:
        path = pathlib.Path(e["directory"], e["file"]).resolve()
        if path.suffix == ".cc" and src in path.parents:
            files[path] = e
    return [files[p] for p in sorted(files)]


def preprocess_command(entry):
    """The entry's compile command with -E to stdout instead of -c FILE -o OBJECT."""
    args = entry["arguments"] if "arguments" in entry else shlex.split(entry["command"])
    if os.path.basename(args[0]) == "ccache":
        args = args[1:]
    out, skip = [], False
    for a in args:
        if skip:
            skip = False
            continue
        if a == "-o":
            skip = True
            continue
        if a == "-c":
            continue
        out.append(a)
    return out + ["-E"]


def fingerprint(entry, salt):
    """sha256 of the salt, the compile command and the preprocessed text, with @ROOT@ for ROOT."""
    args = preprocess_command(entry)
    run = subprocess.run(args, cwd=entry["directory"], capture_output=True, check=False)
    if run.returncode != 0:
        raise RuntimeError(f"{entry['file']}: preprocessing failed:\n"
                           f"{run.stderr.decode(errors='replace')}")
    root = str(ROOT).encode()
    h = hashlib.sha256(salt)
    h.update(" ".join(args).encode().replace(root, b"@ROOT@"))
    h.update(run.stdout.replace(root, b"@ROOT@"))
    return h.hexdigest()


def lint(entry, build_dir, cache, salt):
    """(file, output, clean, from_cache) for one file."""
    key = fingerprint(entry, salt) if cache else None
    if key and (cache / key).exists():
        return entry["file"], "", True, True
    run = subprocess.run(["clang-tidy", "-p", str(build_dir), "--quiet",
                          "--warnings-as-errors=*", entry["file"]],
                         capture_output=True, check=False)
    text = (run.stdout + run.stderr).decode(errors="replace")
    clean = run.returncode == 0 and "warning:" not in text and "error:" not in text
    if clean and key:
        (cache / key).touch()
    return entry["file"], text, clean, False


def main():
    if len(sys.argv) != 4:
        sys.exit(__doc__)
    build_dir = pathlib.Path(sys.argv[1]).resolve()
    jobs = int(sys.argv[2])
    cache = None if sys.argv[3] == "off" else pathlib.Path(sys.argv[3])
    if cache:
        cache.mkdir(parents=True, exist_ok=True)
    version = subprocess.run(["clang-tidy", "--version"], capture_output=True, check=True).stdout
    salt = version + (ROOT / ".clang-tidy").read_bytes()
    entries = compile_commands(build_dir)
    if not entries:
        sys.exit(f"clang_tidy: {build_dir}/compile_commands.json has no src/*.cc file")
    findings, cached, failed = set(), 0, []
    with concurrent.futures.ThreadPoolExecutor(max_workers=jobs) as pool:
        runs = [pool.submit(lint, e, build_dir, cache, salt) for e in entries]
        for r in runs:
            try:
                name, text, clean, from_cache = r.result()
            except RuntimeError as e:
                print(f"clang_tidy: {e}", file=sys.stderr)
                sys.exit(2)
            cached += from_cache
            if not clean:
                failed.append(name)
                findings.update(l for l in text.splitlines() if "warning:" in l or "error:" in l)
                if not any("warning:" in l or "error:" in l for l in text.splitlines()):
                    findings.add(f"{name}: clang-tidy failed:\n{text}")
    for line in sorted(findings):
        print(line)
    print(f"clang_tidy: {len(entries)} files, {cached} clean by their remembered fingerprint, "
          f"{len(entries) - cached} linted now")
    if failed:
        print(f"clang_tidy: FAILED in {len(failed)} files ({len(findings)} findings)", file=sys.stderr)
        sys.exit(1)


if __name__ == "__main__":
    main()
