"""Render the tutorial notebook as a static reStructuredText page of the docs.

    python docs/notebook_page.py            # writes docs/tutorial.rst from examples/tutorial.ipynb
    python docs/notebook_page.py --check    # exit 1 if docs/tutorial.rst is out of date

The notebook's markdown cells use a small subset of Markdown (headings, paragraphs, lists,
emphasis, inline code, ``$...$`` math, indented code blocks), converted here line by line; code
cells become ``code-block:: python``. nbconvert's own RST exporter needs pandoc, and nbsphinx
would execute the notebook at every docs build; tests/test_docs.py checks the page is current.
"""

from __future__ import annotations

import json
import re
import sys
from pathlib import Path

ROOT = Path(__file__).resolve().parent.parent
NOTEBOOK = ROOT / "examples" / "tutorial.ipynb"
PAGE = ROOT / "docs" / "tutorial.rst"
_UNDERLINE = {1: "=", 2: "-", 3: "~"}


def _inline(text: str) -> str:
    text = re.sub(r"(?<!`)`([^`]+)`(?!`)", r"``\1``", text)
    return re.sub(r"\$([^$]+)\$", r":math:`\1`", text)


def markdown_to_rst(source: str) -> str:
    """The notebook's Markdown subset as reStructuredText."""
    out: list[str] = []
    for block in re.split(r"\n\s*\n", source.strip()):
        lines = block.split("\n")
        head = re.match(r"^(#{1,3}) (.*)$", lines[0])
        if head and len(lines) == 1:
            title = _inline(head.group(2))
            out.append(f"{title}\n{_UNDERLINE[len(head.group(1))] * len(title)}")
        elif all(line.startswith("    ") or not line.strip() for line in lines):
            if out and out[-1].endswith(":") and not out[-1].endswith("::"):
                out[-1] += ":"
            elif not out or not out[-1].endswith("::"):
                out.append("::")
            out.append("\n".join(lines))
        else:
            out.append("\n".join(_inline(line) for line in lines))
    return "\n\n".join(out)


def notebook_to_rst(notebook: dict, *, source: str = "examples/tutorial.ipynb") -> str:
    """A whole notebook (as read from JSON) as one reStructuredText page."""
    parts = [f".. This page is generated from {source} by docs/notebook_page.py; edit the notebook."]
    for k, cell in enumerate(notebook["cells"]):
        text = "".join(cell["source"])
        if cell["cell_type"] == "markdown":
            parts.append(markdown_to_rst(text))
            if k == 0:
                parts.append(
                    f"The notebook is ``{source}`` in the repository (solutions: "
                    "``examples/tutorial_solutions.ipynb``); run it with Jupyter to see the figures, "
                    "or read the code here."
                )
        elif cell["cell_type"] == "code" and text.strip():
            body = "\n".join(("   " + line) if line.strip() else "" for line in text.rstrip().split("\n"))
            parts.append(f".. code-block:: python\n\n{body}")
    return "\n\n".join(parts) + "\n"


def main(argv=None) -> int:
    argv = sys.argv[1:] if argv is None else argv
    page = notebook_to_rst(json.loads(NOTEBOOK.read_text(encoding="utf-8")))
    if "--check" in argv:
        current = PAGE.read_text(encoding="utf-8") if PAGE.exists() else ""
        if current != page:
            print(f"{PAGE} is out of date: run python docs/notebook_page.py", file=sys.stderr)
            return 1
        return 0
    PAGE.write_text(page, encoding="utf-8")
    print(f"wrote {PAGE}")
    return 0


if __name__ == "__main__":
    sys.exit(main())
