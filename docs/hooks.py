"""mkdocs hook: the site's home page is the README (one source for the front page), its links
into docs/ made relative to the site."""

from __future__ import annotations

import re
from pathlib import Path


def on_page_markdown(markdown: str, page, config, files) -> str:
    if page.file.src_uri != "index.md":
        return markdown
    readme = (Path(config["docs_dir"]).parent / "README.md").read_text()
    return re.sub(r"\]\(docs/", "](", readme)
