"""The reproduction report's document: content as blocks, rendered to Markdown and to
self-contained HTML (figures inlined)."""

from __future__ import annotations

import base64
import html
from pathlib import Path
from typing import Any


class Doc:
    """Report content as blocks, rendered to Markdown and to self-contained HTML."""

    def __init__(self, root: Path) -> None:
        self.root = root
        self.blocks: list[tuple[str, Any]] = []

    def h(self, level: int, text: str) -> None:
        self.blocks.append(("h", (level, text)))

    def p(self, text: str) -> None:
        self.blocks.append(("p", text))

    def items(self, lines: list[str]) -> None:
        self.blocks.append(("ul", lines))

    def table(self, header: list[str], rows: list[list[str]]) -> None:
        self.blocks.append(("table", (header, rows)))

    def img(self, path: Path, caption: str) -> None:
        self.blocks.append(("img", (path, caption)))

    def markdown(self) -> str:
        out: list[str] = []
        for kind, value in self.blocks:
            if kind == "h":
                out.append("#" * value[0] + " " + value[1])
            elif kind == "p":
                out.append(value)
            elif kind == "ul":
                out.append("\n".join(f"- {line}" for line in value))
            elif kind == "table":
                header, rows = value
                out.append("\n".join(["| " + " | ".join(header) + " |",
                                      "|" + "|".join("---" for _ in header) + "|",
                                      *("| " + " | ".join(r) + " |" for r in rows)]))
            elif kind == "img":
                path, caption = value
                out.append(f"![{caption}]({path.relative_to(self.root).as_posix()})\n\n"
                           f"*{caption}*")
        return "\n\n".join(out) + "\n"

    def html(self, title: str) -> str:
        def inline(text: str) -> str:
            t = html.escape(text)
            parts = t.split("`")
            t = "".join(f"<code>{p}</code>" if i % 2 else p for i, p in enumerate(parts))
            parts = t.split("**")
            return "".join(f"<b>{p}</b>" if i % 2 else p for i, p in enumerate(parts))

        body: list[str] = []
        for kind, value in self.blocks:
            if kind == "h":
                body.append(f"<h{value[0]}>{inline(value[1])}</h{value[0]}>")
            elif kind == "p":
                body.append(f"<p>{inline(value)}</p>")
            elif kind == "ul":
                body.append("<ul>" + "".join(f"<li>{inline(v)}</li>" for v in value) + "</ul>")
            elif kind == "table":
                header, rows = value
                head = "".join(f"<th>{inline(c)}</th>" for c in header)
                trs = "".join("<tr>" + "".join(f"<td>{inline(c)}</td>" for c in r) + "</tr>"
                              for r in rows)
                body.append(f"<table><thead><tr>{head}</tr></thead><tbody>{trs}</tbody></table>")
            elif kind == "img":
                path, caption = value
                data = base64.b64encode(path.read_bytes()).decode()
                body.append(f'<figure><img alt="{html.escape(caption)}" '
                            f'src="data:image/png;base64,{data}"/>'
                            f"<figcaption>{inline(caption)}</figcaption></figure>")
        style = ("body{font-family:sans-serif;max-width:1100px;margin:2em auto;line-height:1.45}"
                 "table{border-collapse:collapse;margin:1em 0}td,th{border:1px solid #bbb;"
                 "padding:3px 8px;text-align:right}th{background:#eee}td:first-child{text-align:"
                 "left}img{max-width:100%}figcaption{font-style:italic;color:#444}"
                 "code{background:#f3f3f3;padding:0 3px}")
        return (f"<!DOCTYPE html><html><head><meta charset='utf-8'><title>{html.escape(title)}"
                f"</title><style>{style}</style></head><body>{''.join(body)}</body></html>\n")
