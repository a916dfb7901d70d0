"""Fast checks that the documentation builds and reads without a network (issue 25).

The full build (``tests/docs/test_docs.py``) checks the rendered pages; these check the
configuration: MathJax is served from the package ``sphinx-mathjax-offline`` (a dependency of the
``docs`` and ``test`` extras) instead of a CDN, nothing shipped points to ../shared, and the
conventions and the architecture are pages of the docs.
"""

import ast
import importlib
import re
from pathlib import Path

import pytest

ROOT = Path(__file__).resolve().parents[2]
DOCS = ROOT / "docs"


def _conf_assignments() -> dict:
    """The literal assignments of docs/conf.py (without running it: it writes generated pages)."""
    out = {}
    for node in ast.parse((DOCS / "conf.py").read_text()).body:
        if isinstance(node, ast.Assign) and len(node.targets) == 1 and isinstance(
                node.targets[0], ast.Name):
            try:
                out[node.targets[0].id] = ast.literal_eval(node.value)
            except ValueError:
                pass
    return out


def test_mathjax_is_served_from_the_local_package():
    conf = _conf_assignments()
    assert "sphinx.ext.mathjax" in conf["extensions"]
    assert "sphinx-mathjax-offline" in conf["extensions"], (
        "MathJax would load from a CDN: add the extension 'sphinx-mathjax-offline'")
    assert not str(conf.get("mathjax_path", "")).startswith(("http:", "https:", "//"))
    ext = pytest.importorskip("sphinx-mathjax-offline")
    static = Path(ext.__file__).parent / "static" / "mathjax"
    assert (static / "tex-chtml.js").is_file()
    assert any((static / "output" / "chtml" / "fonts" / "woff-v2").glob("*.woff"))
    for extras in ("docs", "test"):
        deps = _extras()[extras]
        assert any(d.startswith("sphinx-mathjax-offline") for d in deps), extras


def _extras() -> dict:
    import tomllib

    return tomllib.loads((ROOT / "pyproject.toml").read_text())["project"]["optional-dependencies"]


SHIPPED = [ROOT / "README.md", *sorted(DOCS.rglob("*.md")), *sorted(DOCS.rglob("*.rst")),
           *sorted((ROOT / "notebooks").glob("*.ipynb"))]


@pytest.mark.parametrize("path", [p for p in SHIPPED if "_build" not in p.parts
                                  and "generated" not in p.parts and "notebooks" not in
                                  p.relative_to(DOCS if DOCS in p.parents else ROOT).parts[:1]
                                  or p.suffix == ".ipynb"],
                         ids=lambda p: str(p.relative_to(ROOT)))
def test_nothing_shipped_points_outside_the_repository(path):
    text = path.read_text()
    assert "../shared" not in text and "shared/MODEL.md" not in text, path
    assert not re.search(r"MODEL\.md\s*(s\.|§|section)", text), (
        f"{path.name} cites MODEL.md: cite docs/conventions.md (its sections) instead")


def test_conventions_and_architecture_are_pages_linked_from_readme_and_index():
    index = (DOCS / "index.md").read_text()
    readme = (ROOT / "README.md").read_text()
    for page in ("conventions", "architecture"):
        assert (DOCS / f"{page}.md").is_file(), page
        assert re.search(rf"^{page}$", index, re.M), f"{page} not in the index toctree"
        assert f"docs/{page}.md" in readme, f"README does not link docs/{page}.md"
    conventions = (DOCS / "conventions.md").read_text()
    assert re.search(r"^#+ *8\. Three dimensions", conventions, re.M), "section 8 (3-D) is missing"


def test_getting_started_does_not_ask_for_the_fe_extra():
    text = (DOCS / "getting_started.md").read_text()
    assert not re.search(r"\.\[fe\]|\[fe\]\"? (is )?(needed|required)", text)


def test_notebook_titles_are_numbered_one_way():
    import nbformat

    titles = [nbformat.read(p, as_version=4).cells[0].source.splitlines()[0]
              for p in sorted((ROOT / "notebooks").glob("*.ipynb"))]
    for p, title in zip(sorted((ROOT / "notebooks").glob("*.ipynb")), titles, strict=True):
        assert re.match(rf"^# {p.name[:2]} \u2014 \S", title), title


def test_the_extension_module_is_importable_by_its_sphinx_name():
    importlib.import_module("sphinx-mathjax-offline")


def test_benchmark_headline_commands_are_commands_not_prose(tmp_path):
    """``docs/_ext/generate.py`` takes each RESULTS file's command from a ``Command:`` line or
    the first indented command (with its continuation lines), not from a sentence that begins
    with "Commands (" and quotes a name; every command taken from the repository's RESULTS
    files runs a benchmark script."""
    import sys
    sys.path.insert(0, str(DOCS / "_ext"))
    try:
        generate = importlib.import_module("generate")
    finally:
        sys.path.pop(0)
    res = tmp_path / "bench"
    res.mkdir()
    (res / "RESULTS_x.md").write_text(
        "# X\n\nCommands (from the root; `python3-siconos` from Debian):\n\n"
        "    env $E python3 benchmarks/bench_x.py --n 100 \\\n        --baseline /tmp/base\n"
        "    env $E python3 benchmarks/bench_x.py --parts big\n\n| a | b |\n|---|---|\n| 1 | 2 |\n")
    out = tmp_path / "benchmarks.md"
    generate.benchmark_tables(res, out)
    assert ("Command: `env $E python3 benchmarks/bench_x.py --n 100 --baseline /tmp/base`"
            in out.read_text())
    generate.benchmark_tables(ROOT / "benchmarks", out)
    commands = re.findall(r"^Command: `(.*)`$", out.read_text(), flags=re.M)
    assert commands and all(re.search(r"python3? benchmarks/\S+\.py", c) for c in commands), \
        commands
