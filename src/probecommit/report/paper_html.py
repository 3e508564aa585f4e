"""One self-contained HTML report of the whole reproduction: ``results/paper/report.html``.

REPRODUCTION.md's sections (paper and ours side by side, the note on each gap) rendered as
HTML, each target's figures embedded (PNG, base64) under its section, the same responsive
style as the audit report: readable on a laptop and a phone, no external resource.
"""

from __future__ import annotations

import base64
import html
import re
from pathlib import Path

from probecommit.report.audit_report import _CSS
from probecommit.store.safefile import write_text

#: Target folders whose figures follow each REPRODUCTION.md section (by heading keyword).
SECTION_TARGETS = (("MuJoCo insertion", "insertion"), ("Every family", "breadth"), ("Across engines", "engines"),
                   ("Probe pricing", "cost"), ("learned baseline", "gru"), ("Beyond the paper", "beyond"),
                   ("The robot run", "robot"), ("The task families", "setup"))


def _inline(text: str) -> str:
    out = html.escape(text)
    out = re.sub(r"`([^`]+)`", r"<code>\1</code>", out)
    out = re.sub(r"\*\*([^*]+)\*\*", r"<strong>\1</strong>", out)
    return re.sub(r"\*([^*]+)\*", r"<em>\1</em>", out)


def markdown_html(markdown: str) -> str:
    """The subset of Markdown REPRODUCTION.md uses: headings, paragraphs, pipe tables, lists."""
    blocks, table, para = [], [], []

    def flush() -> None:
        if para:
            blocks.append(f"<p>{_inline(' '.join(para))}</p>")
            para.clear()
        if table:
            rows = [[c.strip() for c in line.strip().strip("|").split("|")] for line in table]
            rows = [r for r in rows if not all(set(c) <= set("-: ") for c in r)]
            head = "".join(f"<th>{_inline(c)}</th>" for c in rows[0])
            body = "".join("<tr>" + "".join(f"<td>{_inline(c)}</td>" for c in r) + "</tr>" for r in rows[1:])
            blocks.append(f"<div class='scroll'><table><thead><tr>{head}</tr></thead><tbody>{body}</tbody></table></div>")
            table.clear()

    for line in markdown.splitlines():
        if line.startswith("|"):
            if para:
                flush()
            table.append(line)
            continue
        if table:
            flush()
        heading = re.match(r"^(#{1,4}) (.*)", line)
        if heading:
            flush()
            level = len(heading.group(1))
            blocks.append(f"<h{level}>{_inline(heading.group(2))}</h{level}>")
        elif not line.strip():
            flush()
        else:
            para.append(line.strip())
    flush()
    return "\n".join(blocks)


def _figures(folder: Path) -> str:
    out = []
    for png in sorted(folder.glob("*.png")):
        data = base64.b64encode(png.read_bytes()).decode("ascii")
        caption = html.escape(png.stem.replace("fig_", "").replace("_", " "))
        out.append(f"<figure><img alt='{caption}' src='data:image/png;base64,{data}'><figcaption>{caption} "
                   f"({html.escape(png.name)}, PDF beside it)</figcaption></figure>")
    return "".join(out)


def write_paper_report(results_root: str | Path, reproduction_md: str | Path, out: str | Path) -> Path:
    """Write the report: REPRODUCTION.md as HTML with each target's figures under its section."""
    results_root, out = Path(results_root), Path(out)
    sections = re.split(r"(?m)^(?=## )", Path(reproduction_md).read_text())
    parts = []
    for section in sections:
        parts.append(markdown_html(section))
        first = section.splitlines()[0] if section.strip() else ""
        for keyword, target in SECTION_TARGETS:
            if first.startswith("## ") and keyword in first and (results_root / target).is_dir():
                parts.append(_figures(results_root / target))
    css = _CSS + "figure{margin:1em 0}figcaption{color:#555;font-size:13px}code{background:#f4f4f4;padding:0 3px}"
    doc = ("<!DOCTYPE html><html><head><meta charset='utf-8'>"
           "<meta name='viewport' content='width=device-width, initial-scale=1'><title>probecommit: reproduction</title>"
           f"<style>{css}</style></head><body>{''.join(parts)}</body></html>")
    write_text(out, doc)
    return out
