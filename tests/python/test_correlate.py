"""impactdic.correlate: known shifts, arrays against files against `impactdic correlate`, the
option errors of the scene keys, sequences, and memory over many calls."""
import resource

import h5py
import numpy as np
import pytest

import impactdic
from conftest import (CLI_OPTIONS, DX, DY, OPTIONS, fourier_shift, interrupt_after, speckle,
                      to_uint16_12bit, to_uint8)

# Subpixel accuracy of a Fourier-shifted 8-bit speckle with the default bicubic B-spline
# interpolation: the median error over the subsets is a few thousandths of a pixel (measured
# 0.002 px); 0.02 px leaves room for the quantization.
SHIFT_TOLERANCE_PX = 0.02


def check_shift(result, dx=DX, dy=DY, row=1):
    valid = result.valid[row]
    assert valid.mean() > 0.9, result.summary["brief_report"]
    assert np.median(result.u[row][valid]) == pytest.approx(dx, abs=SHIFT_TOLERANCE_PX)
    assert np.median(result.v[row][valid]) == pytest.approx(dy, abs=SHIFT_TOLERANCE_PX)


def test_version():
    assert impactdic.__version__
    assert isinstance(impactdic.__version__, str)


@pytest.mark.parametrize("dtype", ["uint8", "uint16"])
def test_shifted_arrays_give_the_shift(pair, pair8, dtype):
    if dtype == "uint8":
        images = pair8
    else:  # 12-bit data in 16-bit words, as a Phantom camera's.
        images = tuple(to_uint16_12bit(image) for image in pair)
    result = impactdic.correlate(*images, **OPTIONS)
    check_shift(result)
    assert result.u.shape == (2, result.x.size) and result.x.shape == result.y.shape
    assert result.u.dtype == np.float64 and result.zncc.dtype == np.float32
    assert result.status.dtype == np.int32 and result.iterations.dtype == np.int32
    assert np.all(result.u[0][result.valid[0]] == 0)  # Row 0: the reference.
    assert list(result.frame) == [0, 1] and list(result.frame_number) == [0, 1]
    assert result.time_s is None  # Arrays carry no time stamps.
    assert result.status_name(0) == "converged"
    assert result.summary["usable"] and result.summary["frames"] == 1
    if dtype == "uint16":
        assert result.summary["data_bits"] == 12


def test_options_nested_and_dotted_are_one(pair8):
    nested = impactdic.correlate(*pair8, dic={"subset_size": 21, "step": 12})
    dotted = impactdic.correlate(*pair8, **{"dic.subset_size": 21, "dic.step": 12})
    np.testing.assert_array_equal(nested.u, dotted.u)
    assert nested.x.size == dotted.x.size


def test_arrays_files_and_cli_agree_to_the_bit(pair8, png_pair, cli, tmp_path):
    arrays = impactdic.correlate(*pair8, **OPTIONS)
    files = impactdic.correlate(*png_pair, **OPTIONS)
    output = str(tmp_path / "dic.h5")
    code, stderr = cli("correlate", "--reference", png_pair[0], "--deformed", png_pair[1],
                       "-o", output, *CLI_OPTIONS)
    assert code == 0, stderr
    with h5py.File(output, "r") as f:
        cli_arrays = {name: f["dic/" + stored][()] for name, stored in [
            ("x", "x_px"), ("y", "y_px"), ("u", "u_px"), ("v", "v_px"), ("status", "status"),
            ("iterations", "iterations"), ("zncc", "zncc"), ("sigma_u", "sigma_u_px"),
            ("sigma_v", "sigma_v_px"), ("frame", "frame"), ("frame_number", "frame_number")]}
    for name, expected in cli_arrays.items():
        np.testing.assert_array_equal(getattr(files, name), expected, err_msg=name)
        np.testing.assert_array_equal(getattr(arrays, name), expected, err_msg=name)
    check_shift(arrays)


def test_sequence_as_a_3d_array(pair8):
    reference = speckle((160, 160), seed=11)
    shifts = [(0.0, 0.0), (0.4, 0.2), (0.9, -0.3), (1.6, -0.7)]
    frames = np.stack([to_uint8(fourier_shift(reference, dx, dy)) for dx, dy in shifts])
    result = impactdic.correlate(frames, **OPTIONS)
    assert result.u.shape[0] == len(shifts)
    for row, (dx, dy) in enumerate(shifts[1:], start=1):
        check_shift(result, dx, dy, row)
    # The same frames as reference and a 3-D array of deformed ones, and as a list.
    as_list = impactdic.correlate(list(frames), **OPTIONS)
    split = impactdic.correlate(frames[0], frames[1:], **OPTIONS)
    np.testing.assert_array_equal(as_list.u, result.u)
    np.testing.assert_array_equal(split.u, result.u)
    timed = impactdic.correlate(frames, time_s=[0.0, 2e-4, 4e-4, 6e-4], **OPTIONS)
    np.testing.assert_array_equal(timed.time_s, [0.0, 2e-4, 4e-4, 6e-4])
    np.testing.assert_array_equal(timed.u, result.u)
    with pytest.raises(ValueError, match="one per frame"):
        impactdic.correlate(frames, time_s=[0.0, 1.0], **OPTIONS)


def test_threads_do_not_change_the_results(pair8):
    one = impactdic.correlate(*pair8, threads=1, **OPTIONS)
    two = impactdic.correlate(*pair8, threads=2, **OPTIONS)
    np.testing.assert_array_equal(one.u, two.u)
    np.testing.assert_array_equal(one.v, two.v)


def test_roi_as_a_list(pair8):
    result = impactdic.correlate(*pair8, dic={"subset_size": 21, "step": 12,
                                              "roi": [40, 40, 150, 150]})
    assert result.x.min() >= 40 and result.x.max() <= 150
    check_shift(result)


def option_error(**options):
    """The message of the ValueError `correlate` raises for `options` on missing files (None when
    it raises none for the options: the files' error comes instead)."""
    try:
        impactdic.correlate("missing_reference.png", "missing_deformed.png", **options)
    except ValueError as e:
        return str(e)
    except OSError:
        return None
    raise AssertionError("correlate of missing files returned")


def cli_error(cli, key, value):
    code, stderr = cli("correlate", "--reference", "missing_reference.png", "--deformed",
                       "missing_deformed.png", "-o", "unused.h5", "--" + key, value)
    assert code != 0
    return stderr.removeprefix("impactdic: error: ").splitlines()[0]


BAD_VALUES = {"dic.subset_size": 4, "dic.step": 0, "dic.interpolation": "nearest-ish",
              "dic.min_zncc": 2.5, "dic.shape": "quintic", "dic.reference_update": "never",
              "preprocess.gaussian.enabled": "maybe", "inputs.fps": -1, "dic.roi": [5, 5, 2, 2],
              "dic.keep_warp_gradient": "perhaps"}


@pytest.mark.parametrize("key", sorted(BAD_VALUES))
def test_bad_option_is_the_clis_value_error(cli, key):
    value = BAD_VALUES[key]
    message = option_error(**{key: value})
    assert message is not None and message.startswith(key + ":"), message
    text = impactdic._key_text(value)
    assert message == cli_error(cli, key, text).replace("--" + key, key)


def test_every_key_refuses_a_bad_value_as_the_cli(cli):
    """Each key the function takes, given text no key of the tables accepts as a number, list or
    enum: the key's parser decides, with the command line's message (keys taking any text, as
    paths, accept it in both)."""
    keys = [k for k in impactdic.correlate_keys if k != "dic.threads"]
    assert "dic.subset_size" in keys and "preprocess.gaussian.enabled" in keys
    refused = 0
    for key in keys:
        message = option_error(**{key: "@bad"})
        expected = cli_error(cli, key, "@bad")
        if message is None:  # Accepted (a path): neither refuses the value itself.
            assert not expected.startswith(f"--{key}: invalid value"), (key, expected)
        else:
            refused += 1
            assert message == expected.replace("--" + key, key), key
    assert refused > len(keys) // 2


def test_unknown_option_names_the_closest_key():
    with pytest.raises(ValueError, match=r"^dic\.subset_sise: unknown option \(did you mean "
                                         r"'dic\.subset_size'\?\); expected a key of the scene's "
                                         r"dic or preprocess section"):
        impactdic.correlate("a.png", "b.png", dic={"subset_sise": 21})
    with pytest.raises(ValueError, match=r"^dic\.bogus: unknown option; expected a key"):
        impactdic.correlate("a.png", "b.png", dic={"bogus": 21})


def test_missing_file_is_an_os_error(tmp_path):
    with pytest.raises(FileNotFoundError, match="missing.png"):
        impactdic.correlate(str(tmp_path / "missing.png"), str(tmp_path / "missing2.png"))


def test_bad_array_is_a_value_error(pair8):
    with pytest.raises(ValueError, match=r"reference: invalid value \(got dtype int64\)"):
        impactdic.correlate(pair8[0].astype(np.int64), pair8[1])
    with pytest.raises(ValueError, match="frame 1: invalid value"):
        impactdic.correlate(pair8[0], np.zeros((4, 5, 3), np.uint8)[..., 0][None, None])
    # Every frame as the reference: its shape and dtype (not left to the frame reader's OSError).
    with pytest.raises(ValueError, match=r"frame 1: invalid value \(got 192x192 uint16\); "
                                         r"expected 192x192 uint8 like the reference"):
        impactdic.correlate(pair8[0], pair8[1].astype(np.uint16))
    with pytest.raises(ValueError, match=r"frame 1: invalid value \(got 100x192 uint8\)"):
        impactdic.correlate(pair8[0], pair8[1][:100])


@pytest.mark.parametrize("dtype", ["float32", "float64"])
def test_float_arrays_are_grey_levels_as_they_are(pair, pair8, dtype):
    """Float images are grey levels as they are, in any range: the speckle in [0, 1] gives the
    shift; the 8-bit images' values as floats give the 8-bit images' results to the last bit
    (the correlator computes in float32 either way; float64 is converted to float32 once)."""
    result = impactdic.correlate(*(image.astype(dtype) for image in pair), **OPTIONS)
    check_shift(result)
    assert result.summary["data_bits"] == 0  # No bit depth: the contrast limits follow the data.
    as_float = impactdic.correlate(*(image.astype(dtype) for image in pair8), **OPTIONS)
    as_uint8 = impactdic.correlate(*pair8, **OPTIONS)
    for name in ("u", "v", "status", "zncc", "iterations"):
        np.testing.assert_array_equal(getattr(as_float, name), getattr(as_uint8, name),
                                      err_msg=name)


@pytest.mark.parametrize("value, found", [(np.nan, "NaN"), (np.inf, "infinity"),
                                          (-np.inf, "infinity")])
def test_non_finite_float_is_a_value_error_naming_the_array(pair, value, found):
    reference, deformed = (image.astype(np.float32) for image in pair)
    bad = deformed.copy()
    bad[3, 5] = value
    with pytest.raises(ValueError, match=rf"^frame 1: invalid value \(got {found} at row 3, "
                                         r"column 5\); expected finite grey levels$"):
        impactdic.correlate(reference, bad, **OPTIONS)
    with pytest.raises(ValueError, match=rf"^reference: invalid value \(got {found} at row 3, "):
        impactdic.correlate(bad, reference, **OPTIONS)


def test_float_arrays_refuse_clahe(pair):
    with pytest.raises(ValueError, match=r"preprocess\.clahe\.enabled: .*8- or 16-bit frames"):
        impactdic.correlate(*(image.astype(np.float32) for image in pair),
                            preprocess={"clahe": {"enabled": True}}, **OPTIONS)


def test_duplicate_image_names_the_python_arguments(png_pair):
    with pytest.raises(ValueError, match=r"^deformed: invalid value \(got '.*reference\.png', the "
                                         r"reference image\); expected each deformed image once"):
        impactdic.correlate(png_pair[0], [png_pair[1], png_pair[0]])
    with pytest.raises(ValueError, match=r"^deformed: invalid value \(got '.*deformed\.png', given "
                                         r"twice\)"):
        impactdic.correlate(png_pair[0], [png_pair[1], png_pair[1]])
    with pytest.raises(ValueError, match=r"^deformed: invalid value \(got missing\); expected at "
                                         r"least one deformed image"):
        impactdic.correlate([png_pair[0]])


def test_progress_callback(pair8):
    """progress(done, total) after each deformed frame; its exception stops the correlation
    (no further frame) and is raised by correlate itself."""
    frames = np.stack([pair8[0], pair8[1], pair8[0], pair8[1]])
    calls = []
    result = impactdic.correlate(frames, progress=lambda done, total: calls.append((done, total)),
                                 **OPTIONS)
    assert calls == [(1, 3), (2, 3), (3, 3)]
    assert result.u.shape[0] == 4

    class Stop(Exception):
        pass

    def stop_at_first(done, total):
        calls.append((done, total))
        raise Stop(f"stopped at {done} of {total}")

    calls.clear()
    with pytest.raises(Stop, match="stopped at 1 of 3"):
        impactdic.correlate(frames, progress=stop_at_first, **OPTIONS)
    assert calls == [(1, 3)]
    with pytest.raises(ValueError, match="progress: invalid value"):
        impactdic.correlate(*pair8, progress=3, **OPTIONS)
    # Still usable after a stop.
    check_shift(impactdic.correlate(*pair8, **OPTIONS))


# A correlation of several seconds in a process of its own: 327,184 subsets (600 x 600, step 1).
LONG_CORRELATION = """
import sys, time
import numpy as np
import impactdic
from conftest import fourier_shift, speckle, to_uint8
reference = speckle((600, 600), seed=3)
pair = to_uint8(reference), to_uint8(fourier_shift(reference, 0.4, 0.2))
print("ready", flush=True)
start = time.monotonic()
try:
    impactdic.correlate(*pair, dic={"subset_size": 21, "step": 1}, threads=2)
    print("finished", flush=True)
except KeyboardInterrupt:
    print("KeyboardInterrupt", flush=True)
"""


@pytest.mark.parametrize("delay_s", [0.3, 1.5])
def test_ctrl_c_interrupts_a_long_correlation(tmp_path, delay_s):
    """SIGINT while the library computes (in the reference's precomputation at 0.3 s, further on
    at 1.5 s; the whole takes 7 s on 2 free cores, twice that when other jobs load them):
    KeyboardInterrupt, neither a hang nor a crash, nothing finished, within 4 s (measured: under
    0.4 s at load 6, up to 2 s at load 8 on the 2-core build machine)."""
    out, ended_s = interrupt_after(LONG_CORRELATION, delay_s, tmp_path)
    assert out == "KeyboardInterrupt"
    assert ended_s < 4.0, f"{ended_s:.2f} s from SIGINT to the end"


def test_result_arrays_are_views_of_the_library_results(pair8):
    """The result's arrays are numpy views of the library's table (no copy): they do not own
    their data and all share one owner, which keeps the table alive after the result is gone."""
    result = impactdic.correlate(*pair8, **OPTIONS)
    arrays = [getattr(result, name) for name in ("x", "y", "u", "v", "sigma_u", "sigma_v", "zncc",
                                                 "status", "iterations", "frame", "frame_number")]
    assert all(not a.flags.owndata for a in arrays)
    assert len({id(a.base) for a in arrays}) == 1
    u = result.u
    expected = u.copy()
    del result, arrays
    import gc
    gc.collect()
    np.testing.assert_array_equal(u, expected)


def test_nothing_usable(pair8):
    flat = np.full_like(pair8[0], 128)
    with pytest.raises(impactdic.NothingUsableError, match="allow_partial"):
        impactdic.correlate(pair8[0], flat, **OPTIONS)
    partial = impactdic.correlate(pair8[0], flat, allow_partial=True, **OPTIONS)
    assert not partial.valid[1].any()
    assert issubclass(impactdic.NothingUsableError, impactdic.Error)


def rss_kb():
    with open("/proc/self/status") as f:
        for line in f:
            if line.startswith("VmRSS:"):
                return int(line.split()[1])
    return resource.getrusage(resource.RUSAGE_SELF).ru_maxrss


def test_memory_bounded_over_many_calls():
    """1,000 correlations of a 128 x 128 pair: the resident memory after the first 100 grows by
    less than 8 MB over the next 900 (measured: 4 kB). Each call copies 32 kB of frames and
    returns about 20 kB of results: leaking either would add 45 MB."""
    reference = to_uint8(speckle((128, 128), seed=3))
    deformed = to_uint8(fourier_shift(speckle((128, 128), seed=3), 0.5, 0.25))
    options = {"dic": {"subset_size": 15, "step": 8}, "threads": 1}
    for _ in range(100):
        impactdic.correlate(reference, deformed, **options)
    before = rss_kb()
    for _ in range(900):
        result = impactdic.correlate(reference, deformed, **options)
    growth_kb = rss_kb() - before
    assert result.summary["usable"] and result.x.size == 196
    assert growth_kb < 8 * 1024, f"RSS grew by {growth_kb} kB over 900 calls"


def test_the_gil_is_released_while_correlating():
    """A Python thread runs while a correlation of a 512 x 512 pair (15,000 subsets) computes: it
    counts far more often than the one time a held GIL would let it in."""
    import threading
    reference = to_uint8(speckle((512, 512), seed=5))
    deformed = to_uint8(fourier_shift(speckle((512, 512), seed=5), 0.7, 0.2))
    done = threading.Event()
    ticks = []

    def count():
        while not done.is_set():
            ticks.append(1)
            done.wait(0.001)

    counter = threading.Thread(target=count)
    counter.start()
    try:
        before = len(ticks)
        result = impactdic.correlate(reference, deformed, threads=1,
                                     dic={"subset_size": 21, "step": 4})
        during = len(ticks) - before
    finally:
        done.set()
        counter.join()
    assert result.summary["seconds"] > 0.05, result.summary["seconds"]  # Long enough to tell.
    assert during >= 10, f"{during} ticks during {result.summary['seconds']:.3f} s"


def test_correlate_from_another_thread(pair8):
    """A correlation started from a Python thread other than the main one (which alone runs
    signal handlers): the same results, and its progress callback called there."""
    import threading
    expected = impactdic.correlate(*pair8, **OPTIONS)
    found, calls = {}, []

    def work():
        found["result"] = impactdic.correlate(
            pair8[0], [pair8[1], pair8[1]], progress=lambda d, t: calls.append((d, t)), **OPTIONS)

    thread = threading.Thread(target=work)
    thread.start()
    thread.join()
    assert calls == [(1, 2), (2, 2)]
    np.testing.assert_array_equal(found["result"].u[1], expected.u[1])
