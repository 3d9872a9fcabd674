"""impactdic.model: the summary of `impactdic model --format json` for the same keys (all but its
wall time), and the keys' messages."""
import json
import subprocess
import os

import pytest

import impactdic

TEST = {"mass_kg": 10, "width_m": 0.15, "drop_height_m": 0.7}


def cli_json(*flags):
    done = subprocess.run([os.environ["IMPACTDIC_CLI"], "model", *flags, "--format", "json"],
                          capture_output=True, text=True, check=False)
    return done.returncode, done.stdout, done.stderr


def without_wall_time(summary):
    return {k: v for k, v in summary.items() if k != "wall_time_s"}


def test_model_is_the_command(tmp_path):
    ours = impactdic.model(test=TEST, **{"model.solver": "dopri5", "model.rtol": 1e-8},
                           output=tmp_path / "series.h5")
    code, out, err = cli_json("--test.mass_kg", "10", "--test.width_m", "0.15",
                              "--test.drop_height_m", "0.7", "--model.solver", "dopri5",
                              "--model.rtol", "1e-08")
    assert code == 0, err
    assert without_wall_time(ours) == without_wall_time(json.loads(out))
    assert ours["steps"] > 0 and ours["crater_depth_m"] > 0
    series = impactdic.read_results(tmp_path / "series.h5")
    assert series.groups  # The series written, readable.


def test_model_errors_are_the_commands():
    with pytest.raises(ValueError) as ours:
        impactdic.model(test=dict(TEST, mass_kg=-1))
    code, _, err = cli_json("--test.mass_kg", "-1", "--test.width_m", "0.15",
                            "--test.drop_height_m", "0.7")
    assert code != 0
    assert str(ours.value) == err.removeprefix("impactdic: error: ").splitlines()[0].replace(
        "--test.mass_kg", "test.mass_kg")
    with pytest.raises(ValueError, match="did you mean 'test.mass_kg'"):
        impactdic.model(test=dict(TEST, mass_k=1))
    with pytest.raises(ValueError, match="expected a number"):
        impactdic.model(test=dict(TEST, width_m="wide"))
