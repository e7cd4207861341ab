"""The README's Python examples run as written, from a directory that holds ``studies/``."""

import pathlib
import re

ROOT = pathlib.Path(__file__).resolve().parents[1]
README = (ROOT / "README.md").read_text()


def example(heading):
    """The first Python block of the README after ``heading``."""
    assert heading in README, f"README lacks the heading {heading!r}"
    match = re.search(r"```python\n(.*?)```", README.split(heading, 1)[1], re.S)
    assert match is not None, f"no Python example after {heading!r}"
    return match.group(1)


def run(code, where, monkeypatch):
    """Run an example in ``where`` (beside a link to studies/); return its namespace."""
    (where / "studies").symlink_to(ROOT / "studies")
    monkeypatch.chdir(where)
    namespace = {}
    exec(compile(code, "README.md", "exec"), namespace)
    return namespace


def test_steady_library_example(tmp_path, monkeypatch):
    ns = run(example("## Library"), tmp_path, monkeypatch)
    assert ns["result"].n == 128 and ns["result"].n_phases == 2, f"result {ns['result']}"


def test_run_in_library_example(tmp_path, monkeypatch):
    ns = run(example("## Run-in (transient)"), tmp_path, monkeypatch)
    result, stored = ns["result"], ns["stored"]
    assert result.success, f"run ended {result.status}: {result.message}"
    assert ns["comparison"].face_error < 1e-6, f"face error {ns['comparison'].face_error}"
    assert stored.steps == result.steps and ns["attrs"]["format_version"] == 3, \
        f"run file: {stored.steps} steps, attributes {ns['attrs']}"
    assert (tmp_path / "out" / "run.png").stat().st_size > 10_000, "figure not drawn"
