"""impactdic.run: a scene run from Python equals `impactdic run` of the same scene to the last
bit (summary.json's bytes, every dataset of results.h5), overrides are the run command's flags."""
import json
import os

import numpy as np
import pytest

import impactdic
from conftest import interrupt_after

SOURCE_DIR = os.path.dirname(os.path.dirname(os.path.dirname(os.path.abspath(__file__))))
SCENE = os.path.join(SOURCE_DIR, "sample_frames", "scene.yaml")
# The outputs compared; the figures and the animation are drawn from the same results.
QUICK = {"outputs": {"figures": False, "animation": False, "csv": False}}
QUICK_FLAGS = ["--outputs.figures", "false", "--outputs.animation", "false", "--outputs.csv",
               "false"]


def test_run_equals_the_cli_to_the_last_bit(tmp_path, cli):
    python_out, cli_out = tmp_path / "python", tmp_path / "cli"
    summary, ours = impactdic.run(SCENE, python_out, threads=2, **QUICK)
    code, stderr = cli("run", SCENE, "-o", str(cli_out), "--threads", "2", *QUICK_FLAGS)
    assert code == 0, stderr
    cli_summary_text = (cli_out / "summary.json").read_text()
    assert summary == json.loads(cli_summary_text)
    assert (python_out / "summary.json").read_text() == cli_summary_text
    assert summary["usable"] is True and summary["p_max_kg_m_s"] > 0
    # The results returned are the file it wrote, read as read_results reads it.
    assert isinstance(ours, impactdic.Results)
    assert os.path.samefile(ours.file, python_out / "results.h5")
    theirs = impactdic.read_results(cli_out / "results.h5")
    compared = 0
    for group in ["dic", "kinematics", "momentum", "time", "model", "sensor"]:
        if group not in theirs.groups:
            continue
        assert group in ours.groups
        for name in theirs[group].datasets:
            np.testing.assert_array_equal(ours[group][name], theirs[group][name],
                                          err_msg=f"/{group}/{name}")
            compared += 1
    assert compared > 30


def test_run_override_is_the_flags(tmp_path, cli):
    with pytest.raises(ValueError) as python_error:
        impactdic.run(SCENE, tmp_path / "out", dic={"subset_size": 4})
    code, stderr = cli("run", SCENE, "-o", str(tmp_path / "out2"), "--dic.subset_size", "4")
    assert code != 0
    cli_message = stderr.removeprefix("impactdic: error: ").splitlines()[0]
    assert str(python_error.value) == cli_message.replace("--dic.subset_size", "dic.subset_size")
    with pytest.raises(ValueError, match="did you mean 'model.K'"):
        impactdic.run(SCENE, tmp_path / "out", model={"k": 1})


def test_run_missing_scene_is_an_os_error(tmp_path):
    with pytest.raises(FileNotFoundError):
        impactdic.run(tmp_path / "missing.yaml")


def test_a_scene_dict(tmp_path, monkeypatch):
    """A scene given as a dict (relative paths against the working folder): five frames of the
    sample correlated and differentiated; its bad value named by the key path."""
    monkeypatch.chdir(SOURCE_DIR)
    scene = {"inputs": {"frames": "sample_frames/frames/frame_000[0-4].png", "mm_per_px": 0.3,
                        "fps": 5000},
             "stages": ["frames", "correlate", "kinematics", "outputs"], **QUICK}
    summary, results = impactdic.run(scene, tmp_path / "out", dic={"subset_size": 25, "step": 32})
    assert summary["usable"] and summary["dic_valid_fraction"] > 0.5
    assert results.dic.u_px.shape[0] == 5 and "kinematics" in results.groups
    np.testing.assert_array_equal(
        results.dic.u_px, impactdic.read_results(tmp_path / "out" / "results.h5").dic.u_px)
    with pytest.raises(ValueError, match=r"\(scene dict\):1: dic\.subset_size: got '4'"):
        impactdic.run(dict(scene, dic={"subset_size": 4}), tmp_path / "out2")


def test_run_without_hdf5_returns_no_results(tmp_path, monkeypatch):
    """outputs.hdf5 false: the summary, and None for the results (no file was written)."""
    monkeypatch.chdir(SOURCE_DIR)
    scene = {"inputs": {"frames": "sample_frames/frames/frame_000[0-4].png", "mm_per_px": 0.3,
                        "fps": 5000},
             "stages": ["frames", "correlate", "kinematics", "outputs"],
             "outputs": {"figures": False, "animation": False, "csv": False, "hdf5": False,
                         "xdmf": False}}
    summary, results = impactdic.run(scene, tmp_path / "out", dic={"subset_size": 25, "step": 32})
    assert summary["usable"] and results is None
    assert not (tmp_path / "out" / "results.h5").exists()


def test_ctrl_c_interrupts_a_run(tmp_path):
    """SIGINT 1 s into the sample scene's run at step 8 (about 6 s of correlation on 2 free
    cores): KeyboardInterrupt within 4 s (measured: 0.1 s), and the output folder as it was (not
    made)."""
    code = f"""
import impactdic
print("ready", flush=True)
try:
    impactdic.run({SCENE!r}, "out", dic={{"step": 8}}, outputs={{"figures": False, "animation": False}})
    print("finished")
except KeyboardInterrupt:
    print("KeyboardInterrupt")
"""
    out, ended_s = interrupt_after(code, 1.0, tmp_path)
    assert out == "KeyboardInterrupt"
    assert ended_s < 4.0, f"{ended_s:.2f} s from SIGINT to the end"
    assert not (tmp_path / "out").exists()
