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

from ..errors import EXCERPT_CHARS, InputError, excerpt, location, printable, require_file
from ..types import INT_LIMIT

__all__ = ["XmlNode", "parse_xml", "xml_int", "xml_float", "read_bytes", "unsafe_xml_reason",
           "tag_text", "MAX_ROWS"]

#: most rows an annotation file may expand to (a ViPER framespan "1:1000000000" is one line but
#: a billion rows; a CVML file written from frames 1 and 10**9 a billion empty frames)
MAX_ROWS = 10_000_000

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
        return f"{location(name, self.line)}: <{tag_text(self.tag)}>"


def tag_text(tag: str) -> str:
    """An element name from a file, for a message: escaped and cut like an excerpt."""
    return printable(tag[:EXCERPT_CHARS]) + ("..." if len(tag) > EXCERPT_CHARS else "")


def unsafe_xml_reason(exc: Exception) -> str:
    """What ``defusedxml`` refused, in words; its own messages quote the file's entity names and
    system identifiers (which may be anything, e.g. ``file:///etc/passwd``)."""
    reasons = {
        "DTDForbidden": "a document type declaration",
        "EntitiesForbidden": "an entity declaration (entity expansion)",
        "ExternalReferenceForbidden": "a reference to an external file or URL",
        "NotSupportedError": "an XML feature the safe parser does not support",
    }
    return reasons.get(type(exc).__name__, "unsafe content")


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
        raise InputError(f"{location(name)}: refused unsafe XML: {unsafe_xml_reason(exc)}") \
            from None
    except xml.sax.SAXParseException as exc:
        # expat's messages ("not well-formed (invalid token)") quote nothing of the file; the
        # column is expat's (0-based)
        raise InputError(f"{location(name, exc.getLineNumber(), exc.getColumnNumber())}: "
                         f"malformed XML: {printable(exc.getMessage())}") from None
    except LookupError:  # an unknown encoding in the XML declaration
        raise InputError(f"{location(name)}: malformed XML: unknown encoding in the XML "
                         "declaration") from None
    except xml.sax.SAXException as exc:
        raise InputError(f"{location(name)}: malformed XML: {printable(exc.getMessage())}") \
            from None
    except ValueError as exc:
        raise InputError(f"{location(name)}: malformed XML ({type(exc).__name__})") from None
    if handler.root is None:
        raise InputError(f"{location(name)}: empty XML document")
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
        raise InputError(f"{node.where(name)}: attribute {key}={excerpt(raw)} is not an "
                         "integer") from None
    if not lo <= v < INT_LIMIT:
        raise InputError(f"{node.where(name)}: attribute {key}={_number_text(raw)} out of "
                         f"range [{lo}, 2**62)")
    return v


def xml_float(node: XmlNode, key: str, name: str) -> float:
    """Attribute ``key`` of ``node`` as a finite float, or :class:`InputError`."""
    raw = _xml_attr(node, key, name)
    try:
        v = float(raw.strip())
    except ValueError:
        raise InputError(f"{node.where(name)}: attribute {key}={excerpt(raw)} is not a "
                         "number") from None
    if not math.isfinite(v):
        raise InputError(f"{node.where(name)}: attribute {key}={excerpt(raw)} is not finite")
    return v


def _number_text(raw: str) -> str:
    """A number from a file for a message: as written when short, else a short excerpt."""
    text = raw.strip()
    return text if len(text) <= EXCERPT_CHARS and text.isprintable() else excerpt(text)


def read_bytes(path: str | Path) -> bytes:
    """The bytes of an annotation file; a missing file or a folder is an :class:`InputError`."""
    return require_file(path, "annotation file").read_bytes()
