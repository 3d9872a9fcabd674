"""The ```py blocks of docs/python.md run as written, in order, in one namespace, from a folder
holding sample_frames/ and calibration/ (links to the repository's), as from a clone."""
import os
import re

SOURCE_DIR = os.path.dirname(os.path.dirname(os.path.dirname(os.path.abspath(__file__))))


def test_python_doc_blocks_run(tmp_path, monkeypatch, capsys):
    with open(os.path.join(SOURCE_DIR, "docs", "python.md")) as f:
        blocks = re.findall(r"^```py\n(.*?)^```$", f.read(), flags=re.M | re.S)
    assert len(blocks) >= 3
    for folder in ("sample_frames", "calibration"):
        os.symlink(os.path.join(SOURCE_DIR, folder), tmp_path / folder)
    monkeypatch.chdir(tmp_path)
    namespace = {}
    for block in blocks:
        exec(compile(block, "docs/python.md", "exec"), namespace)  # noqa: S102 (our own doc)
    out = capsys.readouterr().out
    match = re.search(r"u = (\S+) px, v = (\S+) px", out)
    assert match, out
    assert abs(float(match[1]) - 1.3) < 0.02 and abs(float(match[2]) + 0.6) < 0.02, out
    assert os.path.exists(tmp_path / "results" / "python_sample" / "summary.json")
