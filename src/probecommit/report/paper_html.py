"""One self-contained HTML report of the whole reproduction: ``results/paper/report.html``.

Reading order for a reviewer: a summary first (what the paper claims and how each claim
stands, from ``claims.json`` when the publication has one), a table of contents, then
REPRODUCTION.md's sections (rendered by markdown-it-py, a maintained CommonMark parser
with GFM tables), each followed by its targets' figures with their captions (stored in
the PNG by :func:`probecommit.report.figures.save_figure`). No external resource.
"""

from __future__ import annotations

import base64
import html
import json
import re
from pathlib import Path
from typing import Any

from probecommit.report.audit_report import _CSS, img_tag
from probecommit.store.safefile import write_text

#: Target folders whose figures follow each REPRODUCTION.md section (by heading keyword).
SECTION_TARGETS = (("MuJoCo insertion", "insertion"), ("Every family", "breadth"), ("Across engines", "engines"),
                   ("Probe pricing", "cost"), ("learned baseline", "gru"), ("Beyond the paper", "beyond"),
                   ("The robot run", "robot"), ("The task families", "setup"), ("The task families", "figures"))

_EXTRA_CSS = """
figure{margin:1.2em 0}figcaption{color:#444;font-size:14px;margin-top:0.3em}code{background:#f4f4f4;padding:0 3px}
nav.toc{background:#f7f7f9;border:1px solid #ddd;padding:0.5em 1em;margin:1em 0}nav.toc ol{margin:0.3em 0;padding-left:1.4em}
.status-reproduced,.status-matched{color:#1b7f3b;font-weight:600}.status-differs,.status-failed{color:#b3261e;font-weight:600}
.headline{display:flex;flex-wrap:wrap;gap:0.6em;margin:0.6em 0}.headline div{border:1px solid #ddd;border-radius:6px;padding:0.4em 0.8em}
.headline b{font-size:1.3em;display:block}
figure img{border:1px solid #eee}
table.claims td{text-align:left}
"""


def markdown_html(markdown: str) -> str:
    """CommonMark plus tables (markdown-it-py); wide tables scroll in their own container."""
    from markdown_it import MarkdownIt

    rendered = MarkdownIt("commonmark", {"html": False}).enable("table").render(markdown)
    return rendered.replace("<table>", "<div class='scroll'><table>").replace("</table>", "</table></div>")


def _slug(text: str, used: set[str]) -> str:
    base = re.sub(r"[^a-z0-9]+", "-", re.sub(r"<[^>]+>", "", text).lower()).strip("-") or "section"
    slug, i = base, 2
    while slug in used:
        slug, i = f"{base}-{i}", i + 1
    used.add(slug)
    return slug


def _dpi(png: Path) -> float:
    from PIL import Image

    with Image.open(png) as image:
        return float(image.info.get("Dpi") or (image.info.get("dpi") or (300,))[0])


def _figures(folder: Path) -> str:
    from probecommit.report.figures import min_font_px, read_caption

    out = []
    for png in sorted(folder.glob("*.png")):
        data = base64.b64encode(png.read_bytes()).decode("ascii")
        caption = read_caption(png) or png.stem.replace("fig_", "").replace("_", " ")
        pdf = "; PDF beside it" if png.with_suffix(".pdf").is_file() else ""
        out.append(f"<figure><div class='fig'>{img_tag(data, caption, min_font_px(png), dpi=_dpi(png))}</div>"
                   f"<figcaption>{html.escape(caption)} <span class='note'>({html.escape(png.name)}{pdf})</span>"
                   "</figcaption></figure>")
    return "".join(out)


def _claims_entries(claims: dict[str, Any]) -> list[dict[str, Any]]:
    entries = claims.get("claims", claims.get("entries", []))
    if isinstance(entries, dict):
        entries = [{"id": key, **value} for key, value in entries.items()]
    return list(entries)


def _cell(value: Any) -> str:
    if isinstance(value, dict):
        return "; ".join(f"{html.escape(str(k))} {_cell(v)}" for k, v in value.items())
    if isinstance(value, (list, tuple)):
        return ", ".join(_cell(v) for v in value)
    if isinstance(value, float):
        return f"{value:g}"
    return html.escape("–" if value is None else str(value))


def summary_html(results_root: Path) -> str:
    """The summary: counts by status and every paper item's status, from ``claims.json`` (or a note where absent)."""
    path = results_root / "claims.json"
    if not path.is_file():
        return ("<section id='summary'><h2>Summary</h2><p class='note'>No claims.json in this publication: the status of "
                "each paper item is not computed here. The sections below put the paper's values and ours side by "
                "side.</p></section>")
    try:
        claims = json.loads(path.read_text())
    except ValueError as exc:
        return f"<section id='summary'><h2>Summary</h2><div class='warn'>claims.json unreadable: {html.escape(str(exc))}</div></section>"
    entries = _claims_entries(claims)
    counts = claims.get("counts") or {}
    if not counts:
        for e in entries:
            counts[e.get("status", "?")] = counts.get(e.get("status", "?"), 0) + 1
    head = "".join(f"<div><b>{int(v) if isinstance(v, (int, float)) else html.escape(str(v))}</b>{html.escape(str(k))}</div>"
                   for k, v in counts.items())
    rows = []
    for e in entries:
        status = str(e.get("status", "?"))
        ours = e.get("ours")
        if ours is None and e.get("total") is not None:
            ours = f"{e.get('passed', 0)} of {e.get('total')} comparisons hold"
        rows.append(f"<tr><td data-label='item'>{_cell(e.get('id'))}</td><td data-label='in the paper'>"
                    f"{_cell(e.get('location'))}</td><td class='wrap' data-label='what'>{_cell(e.get('what', ''))}</td>"
                    f"<td class='status-{html.escape(status.split()[0].lower())}' data-label='status'>{_cell(status)}</td>"
                    f"<td class='wrap' data-label='paper'>{_cell(e.get('paper'))}</td>"
                    f"<td class='wrap' data-label='ours'>{_cell(ours)}</td></tr>")
    table = ("<div class='scroll'><table class='claims stack'><thead><tr><th>item</th><th>in the paper</th><th>what</th>"
             "<th>status</th><th>paper</th><th>ours</th></tr></thead><tbody>" + "".join(rows) + "</tbody></table></div>")
    return (f"<section id='summary'><h2>Summary</h2><p>{len(entries)} paper items, by status:</p>"
            f"<div class='headline'>{head}</div>{table}</section>")


def write_paper_report(results_root: str | Path, reproduction_md: str | Path, out: str | Path) -> Path:
    """Write the report: summary, table of contents, REPRODUCTION.md's sections with each target's figures."""
    results_root, out = Path(results_root), Path(out)
    text = Path(reproduction_md).read_text()
    sections = re.split(r"(?m)^(?=## )", text)
    used: set[str] = {"summary", "contents"}
    toc = ["<li><a href='#summary'>Summary</a></li>"]
    parts, placed = [], set()
    for section in sections:
        body = markdown_html(section)
        first = section.splitlines()[0] if section.strip() else ""
        if first.startswith("## "):
            title = first[3:].strip()
            slug = _slug(title, used)
            body = body.replace("<h2>", f"<h2 id='{slug}'>", 1)
            toc.append(f"<li><a href='#{slug}'>{html.escape(title)}</a></li>")
            figures = ""
            for keyword, target in SECTION_TARGETS:
                if keyword in first and (results_root / target).is_dir() and target not in placed:
                    figures += _figures(results_root / target)
                    placed.add(target)
            parts.append(f"<section>{body}{figures}</section>")
        else:  # the title and preamble
            parts.append(body)
    rest = [d for d in sorted(results_root.iterdir()) if d.is_dir() and d.name not in placed and any(d.glob("*.png"))]
    if rest:
        parts.append("<section><h2 id='other-figures'>Other figures</h2>" + "".join(_figures(d) for d in rest) + "</section>")
        toc.append("<li><a href='#other-figures'>Other figures</a></li>")
    intro, sections_html = (parts[0], parts[1:]) if parts and not parts[0].startswith("<section") else ("", parts)
    # the title, then the summary and the contents; the preamble (how the numbers were made) after them
    title = re.match(r"\s*(<h1>.*?</h1>)(.*)", intro, re.S)
    heading, preamble = (title.group(1), title.group(2)) if title else ("<h1>Reproduction</h1>", intro)
    if preamble.strip():
        toc.insert(1, "<li><a href='#about'>How these numbers were made</a></li>")
        preamble = f"<section id='about'><h2>How these numbers were made</h2>{preamble}</section>"
    nav = f"<nav class='toc' id='contents'><b>Contents</b><ol>{''.join(toc)}</ol></nav>"
    css = _CSS + _EXTRA_CSS
    doc = ("<!DOCTYPE html><html lang='en'><head><meta charset='utf-8'>"
           "<meta name='viewport' content='width=device-width, initial-scale=1'><title>probecommit: reproduction</title>"
           f"<style>{css}</style></head><body>{heading}{summary_html(results_root)}{nav}{preamble}{''.join(sections_html)}"
           "</body></html>")
    write_text(out, doc)
    return out
