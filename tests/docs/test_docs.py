"""The documentation's sources: the model-file page names every key the loader accepts (the keys
probed from the loader itself, not listed by hand), the README sections the narrative pages
include are valid reStructuredText once converted, and the README says how to build the pages."""

from __future__ import annotations

import importlib.util
import re
from pathlib import Path

import pytest

ROOT = Path(__file__).resolve().parents[2]
DOCS = ROOT / "docs"


def generate():
    spec = importlib.util.spec_from_file_location("pfaff_docs_generate", DOCS / "generate.py")
    module = importlib.util.module_from_spec(spec)
    spec.loader.exec_module(module)
    return module


def page_sections(text: str) -> dict[str, str]:
    """The model-file page's text under each ````[section]```` / ````[[section]]```` heading."""
    heads = list(
        re.finditer(r"^``\[\[?([\w.]+)\]?\]``(?: and ``\[\[(\w+)\]\]``)?\n~+$", text, re.M)
    )
    out = {}
    for k, h in enumerate(heads):
        end = heads[k + 1].start() if k + 1 < len(heads) else len(text)
        for name in filter(None, h.groups()):
            out[name] = text[h.end() : end]
    return out


def test_the_probe_finds_what_the_loader_refuses():
    """The probe reads the loader's own list: a key it reports is accepted, an unknown one not."""
    from pfaff.modelfile.load import SECTIONS

    keys = generate().loader_keys()
    assert set(SECTIONS) <= set(keys)
    assert "t_end" in keys["simulate"] and "holonomic" in keys["constraints"]
    assert "zz_probe" not in {k for ks in keys.values() for k in ks}


def test_model_file_page_names_every_key_the_loader_accepts():
    keys = generate().loader_keys()
    sections = page_sections((DOCS / "modelfiles.rst").read_text(encoding="utf-8"))
    missing = []
    for section, names in keys.items():
        where = section.split(".")[0]
        if where not in sections:
            missing.append(f"[{section}] (no heading)")
            continue
        missing += [f"[{section}] {n}" for n in names if f"``{n}``" not in sections[where]]
    assert not missing, f"the model-file page does not document: {', '.join(missing)}"


def test_readme_sections_are_valid_restructuredtext():
    docutils = pytest.importorskip("docutils.core")
    gen = generate()
    sections = gen.readme_sections((ROOT / "README.md").read_text(encoding="utf-8"))
    for title in gen.PAGES.values():
        assert title in sections, f"README has no section `## {title}` for the docs"
        rst = gen.to_rst(sections[title])
        # halt at the first warning: unbalanced literals, stray substitutions, bad blocks
        docutils.publish_doctree(
            rst, settings_overrides={"halt_level": 2, "report_level": 2, "warning_stream": False}
        )


def test_conversion_keeps_norms_and_literals():
    gen = generate()
    rst = gen.to_rst("so |f| stays at `constraint_tol` and `Trajectory`s hold λ_N\n")
    assert r"\|f\|" in rst and "``constraint_tol``" in rst and r"``Trajectory``\ s" in rst


def test_readme_links_the_built_pages():
    text = (ROOT / "README.md").read_text(encoding="utf-8")
    assert "docs/_build/html/index.html" in text
    assert "sphinx-build -W -b html docs docs/_build/html" in text
