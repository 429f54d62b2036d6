"""The host names a server of ``serve`` answers to: a ``Host`` header's name in one form, the
names of the address it is bound to and the ``--allowed-host`` names (:func:`allowed_hosts`).
Plain Python, so the command line can check a bind address before the ``serve`` extra is
imported; :mod:`.guard` checks requests against these names."""

from __future__ import annotations

import ipaddress
import re
from typing import Iterable

from ..errors import ConfigError, printable

__all__ = ["LOOPBACK_NAMES", "HOST", "allowed_hosts", "host_name", "is_loopback"]

#: the names a loopback address answers to (IPv6 without its brackets)
LOOPBACK_NAMES = frozenset({"localhost", "127.0.0.1", "::1"})
#: a Host header (RFC 9110 7.2): a name or IPv4 address, or an IPv6 literal in brackets; a port
HOST = re.compile(r"(?:\[(?P<v6>[0-9A-Fa-f:.]+)\]|(?P<name>[A-Za-z0-9._~%!$&'()*+,;=-]+))"
                  r"(?::(?P<port>[0-9]{1,5}))?")


def host_name(text: str) -> str | None:
    """``text`` (a host name or an IP address, IPv6 with or without brackets, no port) as the
    checks compare it: lower case, an IPv6 address in its shortest form without brackets; None
    when it is none of these."""
    if text.startswith("[") and text.endswith("]"):
        text = text[1:-1]
        try:
            return ipaddress.IPv6Address(text).compressed
        except ValueError:
            return None
    if ":" in text:
        try:
            return ipaddress.IPv6Address(text).compressed
        except ValueError:
            return None
    m = HOST.fullmatch(text)
    return text.lower() if m is not None and m["name"] and m["port"] is None else None


def is_loopback(host: str) -> bool:
    """Whether ``host`` (a name or an IP address) is ``localhost`` or a loopback address."""
    if host == "localhost":
        return True
    try:
        return ipaddress.ip_address(host).is_loopback
    except ValueError:
        return False


def _wildcard(host: str) -> bool:
    try:
        return ipaddress.ip_address(host).is_unspecified
    except ValueError:
        return False


def allowed_hosts(bind: str, extra: Iterable[str] = ()) -> frozenset[str] | None:
    """The host names a server listening on ``bind`` answers to, with the ``extra`` names
    (``--allowed-host``); None: any.

    * a loopback address (``127.0.0.1``, ``::1``, ``localhost``): it, ``localhost``,
      ``127.0.0.1`` and ``::1``, and ``extra``;
    * a wildcard address (``0.0.0.0``, ``::``): any name — the names that reach a machine are
      many (its addresses, host names, a reverse proxy's), and ``serve`` requires a token there,
      which a rebinding page does not have — unless ``extra`` names some: then those and the
      loopback names;
    * any other address or name: it and ``extra``.

    Raises
    ------
    ConfigError
        A name of ``extra`` that is not a host name or an IP address (a port, a scheme, a path).
    """
    names = set()
    for value in extra:
        name = host_name(value)
        if name is None:
            raise ConfigError(f"--allowed-host must be a host name or an IP address, without "
                              f"scheme, port or path, got {printable(value)!r}")
        names.add(name)
    own = host_name(bind) or bind.lower()
    if _wildcard(own):
        return frozenset(names | LOOPBACK_NAMES) if names else None
    if is_loopback(own):
        names |= LOOPBACK_NAMES
    return frozenset(names | {own})
