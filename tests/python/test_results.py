"""impactdic.read_results: the groups, datasets, units and descriptions of a results file, as h5py
reads them, and the xarray view."""
import math
import os

import h5py
import numpy as np
import pytest

import impactdic
from conftest import CLI_OPTIONS

SOURCE_DIR = os.path.dirname(os.path.dirname(os.path.dirname(os.path.abspath(__file__))))


@pytest.fixture(scope="module")
def correlate_file(png_pair, cli, tmp_path_factory):
    output = str(tmp_path_factory.mktemp("results") / "dic.h5")
    code, stderr = cli("correlate", "--reference", png_pair[0], "--deformed", png_pair[1],
                       "-o", output, *CLI_OPTIONS)
    assert code == 0, stderr
    return output


def h5py_contents(path):
    """{dataset path: (array, attrs)} and {group path: attrs} of every numeric dataset by h5py."""
    datasets, groups = {}, {"/": dict(h5py.File(path, "r").attrs)}
    with h5py.File(path, "r") as f:
        def visit(name, obj):
            if isinstance(obj, h5py.Group):
                groups["/" + name] = dict(obj.attrs)
            elif obj.dtype.kind in "fiu":
                datasets["/" + name] = (obj[()], dict(obj.attrs))
        f.visititems(visit)
    return datasets, groups


def as_python(value):
    return value.decode() if isinstance(value, bytes) else (
        value.item() if isinstance(value, np.generic) else value)


def same(a, b):
    """Equal, NaN equal to NaN (a figure not measured is NaN)."""
    if isinstance(a, float) and isinstance(b, float) and math.isnan(a) and math.isnan(b):
        return True
    return a == b


@pytest.mark.parametrize("which", ["correlate", "truth"])
def test_every_dataset_and_attribute_as_h5py_reads_it(which, correlate_file):
    path = correlate_file if which == "correlate" else os.path.join(SOURCE_DIR, "sample_frames",
                                                                     "truth.h5")
    results = impactdic.read_results(path)
    datasets, groups = h5py_contents(path)
    assert datasets
    for dataset_path, (expected, attrs) in datasets.items():
        array = results[dataset_path]
        np.testing.assert_array_equal(array, expected, err_msg=dataset_path)
        assert array.shape == expected.shape
        group = results[dataset_path.rsplit("/", 1)[0] or "/"]
        name = dataset_path.rsplit("/", 1)[1]
        for attr, value in attrs.items():
            assert same(group.dataset_attrs[name][attr], as_python(value)), (dataset_path, attr)
    for group_path, attrs in groups.items():
        group = results if group_path == "/" else results[group_path]
        for attr, value in attrs.items():
            assert same(group.attrs[attr], as_python(value)), (group_path, attr)


def test_correlate_file_matches_the_function(correlate_file, png_pair):
    from conftest import OPTIONS
    results = impactdic.read_results(correlate_file)
    direct = impactdic.correlate(*png_pair, **OPTIONS)
    np.testing.assert_array_equal(results.dic.u_px, direct.u)
    assert results.dic.units["u_px"] == "px"
    assert "displacement" in results.dic.descriptions["u_px"]
    assert "codes" in results.dic.dataset_attrs["status"]


def test_to_xarray(correlate_file):
    import xarray  # noqa: F401 (python3-xarray: scripts/install_deps.sh installs it)
    dataset = impactdic.read_results(correlate_file).to_xarray()
    u = dataset["dic_u_px"]
    assert u.dims == ("frame", "subset")
    assert u.attrs["units"] == "px"
    assert dataset["x_px"].dims == ("subset",)
    np.testing.assert_array_equal(dataset["x_px"].values,
                                  impactdic.read_results(correlate_file).dic.x_px)


def test_missing_file_is_an_os_error(tmp_path):
    with pytest.raises(FileNotFoundError):
        impactdic.read_results(tmp_path / "missing.h5")
    not_hdf5 = tmp_path / "text.h5"
    not_hdf5.write_text("not HDF5")
    with pytest.raises(OSError):
        impactdic.read_results(not_hdf5)
