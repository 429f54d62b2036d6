"""Safe XML with line numbers, shared by the CVML and CVAT readers.

:func:`parse_xml` uses ``defusedxml``'s SAX reader (entity declarations and external references
are refused, so "billion laughs" and XXE files raise :class:`~motiontrack.errors.InputError`) and
builds a light tree whose nodes remember their line number, so that errors name the line *and*
the element.
"""

from __future__ import annotations

import io
import math
import xml.sax
from dataclasses import dataclass, field
from pathlib import Path

import defusedxml
import defusedxml.sax

from ..errors import InputError
from ..types import INT_LIMIT

__all__ = ["XmlNode", "parse_xml", "xml_int", "xml_float", "read_bytes"]

@dataclass(eq=False)
class XmlNode:
    """One XML element: qualified ``tag``, attributes, 1-based source ``line``, children, text."""

    tag: str
    attrib: dict[str, str]
    line: int
    children: list["XmlNode"] = field(default_factory=list)
    text: str = ""

    def find_all(self, tag: str) -> list["XmlNode"]:
        return [c for c in self.children if c.tag == tag]

    def find(self, tag: str) -> "XmlNode | None":
        for c in self.children:
            if c.tag == tag:
                return c
        return None

    def where(self, name: str) -> str:
        """``"file.xml:12: <box>"`` for error messages."""
        return f"{name}:{self.line}: <{self.tag}>"


class _TreeBuilder(xml.sax.handler.ContentHandler):
    def __init__(self) -> None:
        super().__init__()
        self.root: XmlNode | None = None
        self._stack: list[XmlNode] = []
        self._text: list[list[str]] = []
        self._locator = None

    def setDocumentLocator(self, locator) -> None:  # noqa: N802 (SAX API)
        self._locator = locator

    def startElement(self, name, attrs) -> None:  # noqa: N802
        line = self._locator.getLineNumber() if self._locator is not None else 0
        node = XmlNode(name, {k: attrs.getValue(k) for k in attrs.getNames()}, int(line or 0))
        if self._stack:
            self._stack[-1].children.append(node)
        else:
            self.root = node
        self._stack.append(node)
        self._text.append([])

    def endElement(self, name) -> None:  # noqa: N802
        node = self._stack.pop()
        node.text = "".join(self._text.pop()).strip()

    def characters(self, content) -> None:
        if self._text:
            self._text[-1].append(content)


def parse_xml(data: bytes, name: str = "<bytes>") -> XmlNode:
    """Parse XML safely into a tree of :class:`XmlNode` (line numbers kept).

    Entity declarations (internal or external) and external DTD/entity references are refused
    (``defusedxml``), which blocks entity-expansion bombs and external-entity (XXE) reads.

    Raises
    ------
    InputError
        Not well-formed (message ``name:line:column: ...``) or unsafe XML.
    """
    handler = _TreeBuilder()
    try:
        defusedxml.sax.parse(io.BytesIO(data), handler, forbid_dtd=False, forbid_entities=True,
                             forbid_external=True)
    except defusedxml.DefusedXmlException as exc:
        raise InputError(f"{name}: refused unsafe XML ({type(exc).__name__}: {exc})") from None
    except xml.sax.SAXParseException as exc:
        raise InputError(f"{name}:{exc.getLineNumber()}:{exc.getColumnNumber()}: malformed XML: "
                         f"{exc.getMessage()}") from None
    except (xml.sax.SAXException, ValueError, LookupError) as exc:
        # LookupError: an unknown encoding in the XML declaration
        raise InputError(f"{name}: malformed XML: {exc}") from None
    if handler.root is None:
        raise InputError(f"{name}: empty XML document")
    return handler.root



def _xml_attr(node: XmlNode, key: str, name: str) -> str:
    """Attribute ``key`` of ``node`` (raw text), or :class:`InputError` when it is missing."""
    raw = node.attrib.get(key)
    if raw is None:
        raise InputError(f"{node.where(name)}: missing attribute {key!r}")
    return raw


def xml_int(node: XmlNode, key: str, name: str, lo: int = -INT_LIMIT) -> int:
    """Attribute ``key`` of ``node`` as an integer in ``[lo, 2**62)``, or :class:`InputError`."""
    raw = _xml_attr(node, key, name)
    try:
        v = int(raw.strip())
    except ValueError:
        raise InputError(f"{node.where(name)}: attribute {key}={raw[:40]!r} is not an integer") \
            from None
    if not lo <= v < INT_LIMIT:
        raise InputError(f"{node.where(name)}: attribute {key}={v} out of range [{lo}, 2**62)")
    return v


def xml_float(node: XmlNode, key: str, name: str) -> float:
    """Attribute ``key`` of ``node`` as a finite float, or :class:`InputError`."""
    raw = _xml_attr(node, key, name)
    try:
        v = float(raw.strip())
    except ValueError:
        raise InputError(f"{node.where(name)}: attribute {key}={raw[:40]!r} is not a number") \
            from None
    if not math.isfinite(v):
        raise InputError(f"{node.where(name)}: attribute {key}={raw[:40]!r} is not finite")
    return v


def read_bytes(path: str | Path) -> bytes:
    p = Path(path)
    if not p.is_file():
        raise InputError(f"annotation file not found: {p}")
    return p.read_bytes()
