"""Numbers that cannot drift: the README's benchmark results are copies of the blocks that the
benchmarks themselves write into docs/benchmarks.md (benchmarks/common.py: publish)."""

from __future__ import annotations

import sys

from cosim.engine.artifacts import ROOT

sys.path.insert(0, str(ROOT / "benchmarks"))
from common import blocks, publish  # noqa: E402


def test_every_benchmark_block_in_the_readme_is_the_one_its_benchmark_wrote():
    readme = blocks((ROOT / "README.md").read_text())
    written = blocks((ROOT / "docs" / "benchmarks.md").read_text())
    assert {"pmsm_drive", "mechanics", "linear_motor", "master", "trade"} <= set(readme)
    for name, block in readme.items():
        assert name in written, f"README block {name} was never written by a benchmark"
        assert block == written[name], f"README block {name} differs from docs/benchmarks.md (edited by hand?)"


def test_the_readme_quotes_no_benchmark_figure_outside_a_written_block():
    """Outside the blocks, the Benchmarks section gives commands and method, no measured times."""
    import re
    text = (ROOT / "README.md").read_text()
    section = text[text.index("## Benchmarks\n"):text.index("\n## ", text.index("## Speed against accuracy") + 3)]
    for block in blocks(section).values():
        section = section.replace(block, "")
    assert not re.search(r"\d+(\.\d+)? ?(ms|s) (CPU|wall)|real-time factor (of )?\d|\d+(\.\d+)?x (less|slower|faster)",
                         section), section


def test_publish_replaces_a_block_in_place_and_appends_a_new_one(tmp_path):
    doc, readme = tmp_path / "benchmarks.md", tmp_path / "README.md"
    readme.write_text("intro\n<!-- benchmark:a -->\nold\n<!-- /benchmark:a -->\nend\n")
    publish("a", "python a.py", ["| x |", "| 1 |"], doc_path=doc, readme_path=readme)
    publish("b", "python b.py", ["two"], doc_path=doc, readme_path=readme)
    publish("a", "python a.py", ["| x |", "| 2 |"], doc_path=doc, readme_path=readme)
    written = blocks(doc.read_text())
    assert list(written) == ["a", "b"]
    assert "| 2 |" in written["a"] and "| 1 |" not in written["a"]
    assert blocks(readme.read_text()) == {"a": written["a"]}
    assert readme.read_text().startswith("intro\n") and readme.read_text().endswith("\nend\n")
