"""The reference pages (docs/reference/) are what the schemas and the command line's parsers
generate: a key added to a schema, or an option to a command, shows in the docs or fails here."""

from __future__ import annotations

import importlib.util

from cosim.engine.artifacts import ROOT


def test_the_reference_pages_are_generated_from_the_schemas_and_the_parsers():
    spec = importlib.util.spec_from_file_location("reference", ROOT / "scripts" / "reference.py")
    reference = importlib.util.module_from_spec(spec)
    spec.loader.exec_module(reference)
    pages = reference.pages()
    assert {"scene.md", "study.md", "settings.md", "sweep.md", "cli.md"} <= set(pages)
    for name, text in pages.items():
        page = ROOT / "docs" / "reference" / name
        assert page.is_file() and page.read_text() == text, \
            f"{page} is out of date: run `.venv/bin/python scripts/reference.py`"
