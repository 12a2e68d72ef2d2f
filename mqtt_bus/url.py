"""Where the bus connects: `mqtt://user:pass@host:port/prefix` (TLS: `mqtts://`)."""

from __future__ import annotations

import ssl
import urllib.parse
from dataclasses import dataclass

from mqtt_bus.topics import DEFAULT_PREFIX, check_prefix

__all__ = ["BrokerUrl", "parse_broker_url"]

PLAIN_PORT = 1883
TLS_PORT = 8883


@dataclass(frozen=True, slots=True)
class BrokerUrl:
    """A parsed broker URL. `ca_file`: a CA bundle for `mqtts` (query `?ca=FILE`; default:
    the system's)."""

    host: str
    port: int
    tls: bool = False
    username: str | None = None
    password: str | None = None
    prefix: str = DEFAULT_PREFIX
    ca_file: str | None = None

    def tls_context(self) -> ssl.SSLContext | None:
        if not self.tls:
            return None
        return ssl.create_default_context(cafile=self.ca_file)

    def redacted(self) -> str:
        """The URL without its password, for logs and messages."""
        scheme = "mqtts" if self.tls else "mqtt"
        user = f"{self.username}@" if self.username else ""
        return f"{scheme}://{user}{self.host}:{self.port}/{self.prefix}"


def parse_broker_url(text: str) -> BrokerUrl:
    """Parse a broker URL; ValueError naming what is wrong."""
    if not isinstance(text, str) or not text.strip():
        raise ValueError("the MQTT URL is empty; expected mqtt://[user:pass@]host[:port][/prefix]")
    parts = urllib.parse.urlsplit(text.strip())
    if parts.scheme not in ("mqtt", "mqtts"):
        raise ValueError(f"MQTT URL {text!r}: the scheme must be mqtt:// or mqtts://, "
                         f"not {parts.scheme + '://' if parts.scheme else 'none'}")
    try:
        port = parts.port
    except ValueError as error:
        raise ValueError(f"MQTT URL {text!r}: {error}") from None
    if not parts.hostname:
        raise ValueError(f"MQTT URL {text!r} names no host")
    if port == 0:
        raise ValueError(f"MQTT URL {text!r}: port 0 is not a broker port")
    if "#" in text:
        raise ValueError(f"MQTT URL {text!r}: '#' is a topic wildcard and cannot be an MQTT "
                         "topic level of the prefix")
    tls = parts.scheme == "mqtts"
    prefix = urllib.parse.unquote(parts.path.strip("/")) or DEFAULT_PREFIX
    check_prefix(prefix)
    query = urllib.parse.parse_qs(parts.query, keep_blank_values=True)
    unknown = sorted(set(query) - {"ca"})
    if unknown:
        raise ValueError(f"MQTT URL {text!r}: unknown option {unknown[0]!r} (known: ca)")
    ca = query.get("ca", [None])[-1]
    if ca is not None and not tls:
        raise ValueError(f"MQTT URL {text!r}: ?ca= applies to mqtts:// only")
    return BrokerUrl(
        host=parts.hostname, port=port or (TLS_PORT if tls else PLAIN_PORT), tls=tls,
        username=urllib.parse.unquote(parts.username) if parts.username else None,
        password=urllib.parse.unquote(parts.password) if parts.password is not None else None,
        prefix=prefix, ca_file=ca or None,
    )
