"""Shared fixtures of the Python module's tests: speckle images under a known shift, written as
greyscale PNG when a test needs files, and the command-line tool of the same build."""
import os
import struct
import subprocess
import zlib

import numpy as np
import pytest

import impactdic

# The shift of the deformed image [px]: deformed(x, y) = reference(x - DX, y - DY).
DX, DY = 1.3, -0.6
SIZE = 192  # Image side [px]: 100 subsets of 21 px at step 12, well inside.


def speckle(shape, seed, sigma_px=1.5):
    """Band-limited random speckle (white noise smoothed by a Gaussian of sigma_px), periodic, so
    that a Fourier shift moves it exactly; float64 in [0, 1]."""
    rng = np.random.default_rng(seed)
    spectrum = np.fft.fft2(rng.random(shape))
    ky = np.fft.fftfreq(shape[0])[:, None]
    kx = np.fft.fftfreq(shape[1])[None, :]
    spectrum *= np.exp(-2 * (np.pi * sigma_px) ** 2 * (kx ** 2 + ky ** 2))
    image = np.fft.ifft2(spectrum).real
    return (image - image.min()) / (image.max() - image.min())


def fourier_shift(image, dx, dy):
    """image moved by (dx, dy) px: out(x, y) = image(x - dx, y - dy), periodic."""
    ky = np.fft.fftfreq(image.shape[0])[:, None]
    kx = np.fft.fftfreq(image.shape[1])[None, :]
    phase = np.exp(-2j * np.pi * (kx * dx + ky * dy))
    return np.fft.ifft2(np.fft.fft2(image) * phase).real


def to_uint8(image):
    return np.clip(np.rint(20 + 215 * image), 0, 255).astype(np.uint8)


def to_uint16_12bit(image):
    return np.clip(np.rint(200 + 3700 * image), 0, 4095).astype(np.uint16)


def write_png(path, image):
    """A greyscale PNG (8- or 16-bit) of a 2-D uint8 or uint16 array."""
    bits = 8 if image.dtype == np.uint8 else 16
    raw = image.astype(">u2").tobytes() if bits == 16 else image.tobytes()
    row = image.shape[1] * bits // 8
    data = b"".join(b"\0" + raw[r * row:(r + 1) * row] for r in range(image.shape[0]))

    def chunk(kind, body):
        return (struct.pack(">I", len(body)) + kind + body +
                struct.pack(">I", zlib.crc32(kind + body) & 0xFFFFFFFF))

    header = struct.pack(">IIBBBBB", image.shape[1], image.shape[0], bits, 0, 0, 0, 0)
    with open(path, "wb") as f:
        f.write(b"\x89PNG\r\n\x1a\n" + chunk(b"IHDR", header) +
                chunk(b"IDAT", zlib.compress(data)) + chunk(b"IEND", b""))


@pytest.fixture(scope="session")
def pair():
    """(reference, deformed) float64 speckle in [0, 1], deformed shifted by (DX, DY)."""
    reference = speckle((SIZE, SIZE), seed=7)
    return reference, fourier_shift(reference, DX, DY)


@pytest.fixture(scope="session")
def pair8(pair):
    return tuple(to_uint8(image) for image in pair)


@pytest.fixture(scope="session")
def png_pair(pair8, tmp_path_factory):
    folder = tmp_path_factory.mktemp("png")
    paths = [str(folder / "reference.png"), str(folder / "deformed.png")]
    for path, image in zip(paths, pair8):
        write_png(path, image)
    return paths


@pytest.fixture(scope="session")
def cli():
    """Runs the build's `impactdic` with the arguments; (exit code, stderr)."""
    program = os.environ.get("IMPACTDIC_CLI")
    assert program, "IMPACTDIC_CLI names the command-line tool (set by CTest)"

    def run(*args):
        done = subprocess.run([program, *args], capture_output=True, text=True, check=False)
        return done.returncode, done.stderr

    return run


def interrupt_after(code, delay_s, folder):
    """Runs the Python `code` in a process of its own (this folder's modules importable; working
    folder `folder`), sends it SIGINT `delay_s` after it printed "ready": (what it printed after,
    stripped; seconds from the signal to its end). Fails if it exits with an error or does not
    end within 20 s (killed)."""
    import signal
    import sys
    import time
    script = os.path.join(folder, "interrupted.py")
    with open(script, "w") as f:
        f.write(code)
    env = dict(os.environ, PYTHONPATH=os.pathsep.join(
        [os.environ.get("PYTHONPATH", ""), os.path.dirname(os.path.abspath(__file__))]))
    process = subprocess.Popen([sys.executable, script], stdout=subprocess.PIPE,
                               stderr=subprocess.PIPE, text=True, env=env, cwd=folder)
    try:
        assert process.stdout.readline().strip() == "ready"
        time.sleep(delay_s)
        sent = time.monotonic()
        process.send_signal(signal.SIGINT)
        out, err = process.communicate(timeout=20)
        ended_s = time.monotonic() - sent
    finally:
        if process.poll() is None:
            process.kill()
            process.wait()
    assert process.returncode == 0, err
    return out.strip(), ended_s


# Small, fast options shared by the tests (the defaults but the subset size and step).
OPTIONS = {"dic": {"subset_size": 21, "step": 12}}
CLI_OPTIONS = ["--dic.subset_size", "21", "--dic.step", "12"]


def pytest_report_header(config):
    return f"impactdic {impactdic.__version__} from {os.path.dirname(impactdic.__file__)}"
