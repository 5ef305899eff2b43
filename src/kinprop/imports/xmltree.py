"""A small XML element tree that remembers line numbers (for located errors).

:mod:`xml.etree.ElementTree` drops source lines; expat gives them. Documents that declare
entities (``<!ENTITY``) are refused before parsing (no entity expansion, no external
resources), so a hostile file cannot blow up memory or reach the network.
"""

from __future__ import annotations

from collections.abc import Iterator
from dataclasses import dataclass, field
from xml.parsers import expat

from kinprop.errors import ModelError, Problem


@dataclass
class Node:
    """One XML element: tag, attributes, children and the line it starts on."""

    tag: str
    attrib: dict[str, str]
    line: int
    children: list[Node] = field(default_factory=list)
    parent: Node | None = field(default=None, repr=False)

    def __iter__(self) -> Iterator[Node]:
        return iter(self.children)

    def get(self, key: str, default: str | None = None) -> str | None:
        return self.attrib.get(key, default)

    def where(self) -> str:
        """``line N <tag name='x'>`` for messages."""
        name = self.attrib.get("name")
        label = f"<{self.tag} name={name!r}>" if name else f"<{self.tag}>"
        return f"line {self.line} {label}"


def parse_xml(text: str, file: str) -> Node:
    """Parse ``text``; a syntax error or an entity declaration is a located :class:`ModelError`."""
    if "<!ENTITY" in text:
        line = text[: text.index("<!ENTITY")].count("\n") + 1
        raise ModelError([Problem(f"line {line}", "entity declarations are not accepted in MJCF files", file)])
    parser = expat.ParserCreate()
    stack: list[Node] = []
    root: list[Node] = []

    def start(tag: str, attrs: dict[str, str]) -> None:
        node = Node(tag, dict(attrs), parser.CurrentLineNumber, parent=stack[-1] if stack else None)
        if stack:
            stack[-1].children.append(node)
        else:
            root.append(node)
        stack.append(node)

    def end(tag: str) -> None:
        stack.pop()

    parser.StartElementHandler = start
    parser.EndElementHandler = end
    try:
        parser.Parse(text, True)
    except expat.ExpatError as exc:
        raise ModelError(
            [Problem(f"line {exc.lineno}, column {exc.offset}", f"malformed XML: {expat.ErrorString(exc.code)}", file)]
        ) from None
    if not root:
        raise ModelError([Problem("file", "no XML element found", file)])
    return root[0]
