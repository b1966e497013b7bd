"""Numbers that cannot drift: the benchmark results the user guide (docs/guide/*.md) and the README
quote are copies of the blocks that the benchmarks themselves write into docs/benchmarks.md
(benchmarks/common.py: publish)."""

from __future__ import annotations

import sys

from cosim.engine.artifacts import ROOT

sys.path.insert(0, str(ROOT / "benchmarks"))
from common import QUOTING, blocks, publish  # noqa: E402


def test_every_quoted_benchmark_block_is_the_one_its_benchmark_wrote():
    written = blocks((ROOT / "docs" / "benchmarks.md").read_text())
    quoted = {}
    for page in QUOTING:
        for name, block in blocks(page.read_text()).items():
            assert name in written, f"{page.name}: block {name} was never written by a benchmark"
            assert block == written[name], f"{page.name}: block {name} differs from docs/benchmarks.md (edited by hand?)"
            quoted[name] = page
    assert {"pmsm_drive", "mechanics", "linear_motor", "master", "trade"} <= set(quoted)


def test_the_guide_quotes_no_benchmark_figure_outside_a_written_block():
    """Outside the blocks, the Benchmarks page gives commands and method, no measured times."""
    import re
    text = (ROOT / "docs" / "guide" / "performance.md").read_text()
    section = text[:text.index("## Speed against accuracy")]
    for block in blocks(section).values():
        section = section.replace(block, "")
    assert not re.search(r"\d+(\.\d+)? ?(ms|s) (CPU|wall)|real-time factor (of )?\d|\d+(\.\d+)?x (less|slower|faster)",
                         section), section


def test_publish_replaces_a_block_in_place_and_appends_a_new_one(tmp_path):
    doc, page = tmp_path / "benchmarks.md", tmp_path / "scenes.md"
    page.write_text("intro\n<!-- benchmark:a -->\nold\n<!-- /benchmark:a -->\nend\n")
    publish("a", "python a.py", ["| x |", "| 1 |"], doc_path=doc, quoting=(page,), write=True)
    publish("b", "python b.py", ["two"], doc_path=doc, quoting=(page,), write=True)
    publish("a", "python a.py", ["| x |", "| 2 |"], doc_path=doc, quoting=(page,), write=True)
    before = (doc.read_text(), page.read_text())
    publish("a", "python a.py", ["| x |", "| 3 |"], doc_path=doc, quoting=(page,))  # no --write: printed only
    assert (doc.read_text(), page.read_text()) == before
    written = blocks(doc.read_text())
    assert list(written) == ["a", "b"]
    assert "| 2 |" in written["a"] and "| 1 |" not in written["a"]
    assert blocks(page.read_text()) == {"a": written["a"]}
    assert page.read_text().startswith("intro\n") and page.read_text().endswith("\nend\n")
