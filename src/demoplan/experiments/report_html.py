"""A self-contained HTML page of a markdown report (``report.html`` beside
``report.md``): the markdown rendered with markdown-it (CommonMark and tables,
already installed with rich), every local image and video embedded as a data
URI, so the page opens anywhere as one file.
"""

from __future__ import annotations

import base64
import html
import re
from pathlib import Path

from markdown_it import MarkdownIt
from markdown_it.token import Token

__all__ = ["markdown_to_html"]

_VIDEO_SOURCE = re.compile(r'src="([^":]+\.mp4)"')
MEDIA_TYPES = {
    ".png": "image/png",
    ".svg": "image/svg+xml",
    ".jpg": "image/jpeg",
    ".jpeg": "image/jpeg",
    ".gif": "image/gif",
    ".mp4": "video/mp4",
}
"""The media type of each kind of file a report embeds, fixed here rather
than read from the machine's MIME tables (``mimetypes`` reads
``/etc/mime.types`` and the like): the page does not depend on the machine,
and the command opens no file it was not given (docs/limits.md, "What
demoplan opens")."""

_STYLE = """
body { font-family: system-ui, sans-serif; max-width: 70rem; margin: 2rem auto;
       padding: 0 1rem; line-height: 1.45; color: #222; }
table { border-collapse: collapse; margin: 1rem 0; font-size: 0.92rem; }
th, td { border: 1px solid #ccc; padding: 0.25rem 0.6rem; text-align: left; }
th { background: #f3f3f3; }
img { max-width: 100%; height: auto; border: 1px solid #eee; }
code, pre { background: #f6f6f6; font-size: 0.9rem; }
pre { padding: 0.6rem; overflow-x: auto; }
"""


def markdown_to_html(markdown: str, folder: Path, title: str) -> str:
    """The HTML page of ``markdown``, whose relative image paths are read from
    ``folder`` and embedded. An image that is missing stays a link (and shows
    as broken, which the report test catches)."""
    parser = MarkdownIt("commonmark").enable("table")
    tokens = parser.parse(markdown)
    for token in _walk(tokens):
        if token.type == "image":
            source = str(token.attrGet("src") or "")
            embedded = _data_uri(folder, source)
            if embedded is not None:
                token.attrSet("src", embedded)
        elif token.type in ("html_block", "html_inline"):  # a <video src="…">
            token.content = _VIDEO_SOURCE.sub(
                lambda m: f'src="{_data_uri(folder, m.group(1)) or m.group(1)}"', token.content
            )
    body = parser.renderer.render(tokens, parser.options, {})
    return (
        '<!DOCTYPE html>\n<html lang="en">\n<head>\n<meta charset="utf-8">\n'
        f"<title>{html.escape(title)}</title>\n<style>{_STYLE}</style>\n</head>\n"
        f"<body>\n{body}</body>\n</html>\n"
    )


def _walk(tokens: list[Token]) -> list[Token]:
    found: list[Token] = []
    for token in tokens:
        found.append(token)
        if token.children:
            found += _walk(token.children)
    return found


def _data_uri(folder: Path, source: str) -> str | None:
    """``source`` as a data URI when it names a file inside ``folder``."""
    if ":" in source or source.startswith("/"):
        return None  # a URL or an absolute path: left as written
    path = (folder / source).resolve()
    if not path.is_file() or not path.is_relative_to(folder.resolve()):
        return None
    kind = MEDIA_TYPES.get(path.suffix.lower(), "application/octet-stream")
    return f"data:{kind};base64,{base64.b64encode(path.read_bytes()).decode('ascii')}"
