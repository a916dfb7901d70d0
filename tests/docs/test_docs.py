"""The Sphinx documentation builds with no warning (-W), no network, from executed notebooks."""

import html
import importlib
import os
import re
import subprocess
import sys
from pathlib import Path

import pytest

ROOT = Path(__file__).resolve().parents[2]
NOTEBOOKS = sorted((ROOT / "notebooks").glob("*.ipynb"))


@pytest.fixture(scope="module")
def built_docs(tmp_path_factory, executed_notebooks):
    for module in ("sphinx", "myst_nb", "numpydoc", "pydata_sphinx_theme"):
        pytest.importorskip(module)
    for path in NOTEBOOKS:  # executed once per session, shared with tests/test_notebooks.py
        executed_notebooks(path)
    out = tmp_path_factory.mktemp("docs")
    env = {**os.environ, "SHAKEDOWN_DOCS_NOTEBOOKS": str(executed_notebooks.folder),
           "PYTHONPATH": os.pathsep.join([str(ROOT), os.environ.get("PYTHONPATH", "")])}
    r = subprocess.run(
        [sys.executable, "-m", "sphinx", "-W", "--keep-going", "-q", "-E", "-b", "html",
         "-d", str(out / "doctrees"), str(ROOT / "docs"), str(out / "html")],
        capture_output=True, text=True, env=env, timeout=900)
    return r, out / "html"


def test_docs_build_without_warnings(built_docs):
    r, html_dir = built_docs
    assert r.returncode == 0, r.stderr[-4000:]
    assert r.stderr.strip() == "", r.stderr[-4000:]
    assert (html_dir / "index.html").is_file()


def test_notebooks_are_rendered_with_their_figures(built_docs, executed_notebooks):
    _, html_dir = built_docs
    for path in NOTEBOOKS:
        _, error = executed_notebooks(path)
        page = html_dir / "notebooks" / f"{path.stem}.html"
        assert page.is_file(), path.name
        if error is None:  # a failing notebook is reported by its own test
            n_png = sum(
                1 for c in executed_notebooks(path)[0].cells if c.cell_type == "code"
                for o in c.get("outputs", []) if "image/png" in o.get("data", {}))
            if n_png:
                assert page.read_text().count("<img") >= n_png, path.name


def test_scene_reference_lists_every_option_the_code_accepts(built_docs):
    """Generated from the OPTIONS schemas and the builders' keys at build time: no drift."""
    from shakedown.scenes import files

    _, html_dir = built_docs
    text = html.unescape(re.sub(r"<[^>]+>", "", (html_dir / "generated" /
                                                 "scene_reference.html").read_text()))
    for name, module in files.ANALYSES.items():
        mod = importlib.import_module(module)
        assert f"[analyses.{name}]" in text
        for key, (_, _, help_) in mod.OPTIONS.items():
            assert key in text and help_.split("(")[0].strip()[:30] in text, (name, key)
    for kind, module in files.MODEL_KINDS.items():
        mod = importlib.import_module(module)
        assert f'kind = "{kind}"' in text
        for key in mod.MODEL_KEYS:
            assert key in text, (kind, key)


def test_benchmark_headlines_come_from_the_results_files(built_docs):
    _, html_dir = built_docs
    text = (html_dir / "generated" / "benchmarks.html").read_text()
    for res in sorted((ROOT / "benchmarks").glob("RESULTS_*.md")):
        assert res.name in text


def _pages(html_dir):
    return sorted(p for p in html_dir.rglob("*.html") if "_static" not in p.parts
                  and "_modules" not in p.parts)


def test_pages_load_nothing_from_the_network_and_math_has_its_local_mathjax(built_docs):
    """Offline reading (issue 25: MathJax came from a CDN, so every formula showed as raw LaTeX
    without a network).  Every script a page loads is a file of the build; a page with math
    loads MathJax from ``_static/mathjax``."""
    _, html_dir = built_docs
    with_math = []
    for page in _pages(html_dir):
        text = page.read_text()
        for src in re.findall(r"<script[^>]*\ssrc=\"([^\"]+)\"", text):
            assert not re.match(r"^(https?:)?//", src), f"{page.name} loads {src} from the network"
            assert (page.parent / src.split("?")[0]).is_file(), f"{page.name}: {src} missing"
        if 'class="math' in text:
            with_math.append(page.relative_to(html_dir).as_posix())
            assert re.search(r"<script[^>]*src=\"[^\"]*_static/mathjax/tex-chtml\.js", text), page
    assert "conventions.html" in with_math and "notebooks/04_monte_carlo.html" in with_math
    fonts = html_dir / "_static" / "mathjax" / "output" / "chtml" / "fonts" / "woff-v2"
    assert any(fonts.glob("*.woff")), "MathJax fonts not copied"


def test_no_page_shows_raw_latex_outside_math(built_docs):
    """TeX outside the math elements MathJax typesets (a ``$...$`` that was not parsed as math,
    say) would show raw: none outside code."""
    _, html_dir = built_docs
    for page in _pages(html_dir):
        text = page.read_text()
        body = text[text.find("<article"):text.rfind("</article>")] if "<article" in text else ""
        body = re.sub(r"<(span|div) class=\"math[^\"]*\">.*?</\1>", "", body, flags=re.S)
        body = re.sub(r"<(pre|code|script|style)[^>]*>.*?</\1>", "", body, flags=re.S)
        body = html.unescape(re.sub(r"<[^>]+>", "", body))
        raw = re.findall(r"\$\$|\$[^$\n]*\\(?:lambda|frac|mu|bar|cos|sin|pi)\b[^$\n]*\$|\\\[|\\begin\{", body)
        assert not raw, f"{page.relative_to(html_dir)}: raw LaTeX {raw[:3]}"
