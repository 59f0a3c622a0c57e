"""Zenoh configurations for faultmas: safe by default, so nothing leaves the machine unless asked.

Embedded default (``ZenohOptions()``): peer mode, multicast scouting OFF (always: faultmas never
scouts the LAN), one explicit loopback listen endpoint on a free port, gossip scouting on (it only
passes on the endpoints peers already listen on, over links they already have, so a process that
connects to the launcher also finds the launcher's other children), shared memory off, and a short
link lease (1 s, keep-alive every 250 ms) so an agent whose host freezes or loses the network is
declared gone within about a second (a killed process is seen in milliseconds: its TCP link closes).

Security (TLS, user/password, access control) comes from a Zenoh JSON5 file (``config_file``), see
docs/deployment.md. The file is the base; a faultmas setting is applied on top only where the file
leaves Zenoh's default, so the file wins for every key it sets.
"""
from __future__ import annotations

import json
import socket
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

MODES = ("peer", "client", "router")

#: Default link lease (ms) and keep-alives per lease: failure detection without a TCP FIN in ~1 s.
DEFAULT_LEASE_MS = 1000
DEFAULT_KEEP_ALIVE = 4


def free_port(host: str = "127.0.0.1") -> int:
    """A TCP port free right now on ``host`` (for an explicit listen endpoint)."""
    with socket.socket() as sock:
        sock.bind((host, 0))
        return int(sock.getsockname()[1])


def loopback_endpoint(port: int | None = None) -> str:
    """``tcp/127.0.0.1:<port>``, a free port when none is given."""
    return f"tcp/127.0.0.1:{port if port is not None else free_port()}"


@dataclass
class ZenohOptions:
    """What faultmas sets in a Zenoh configuration; ``build_config`` turns it into a ``zenoh.Config``."""

    mode: str = "peer"
    listen: tuple[str, ...] | None = None   # None: one free loopback port (peer, router); none (client)
    connect: tuple[str, ...] = ()
    lease_ms: int = DEFAULT_LEASE_MS
    keep_alive: int = DEFAULT_KEEP_ALIVE
    gossip: bool = True
    shared_memory: bool = False
    config_file: str | Path | None = None   # Zenoh JSON5: TLS, usrpwd, access control, endpoints
    extra: dict[str, Any] = field(default_factory=dict)  # raw overrides, e.g. {"adminspace/enabled": True}

    def __post_init__(self) -> None:
        if self.mode not in MODES:
            raise ValueError(f"invalid Zenoh mode {self.mode!r}; expected one of {', '.join(MODES)}")
        if self.lease_ms <= 0 or self.keep_alive <= 0:
            raise ValueError("lease_ms and keep_alive must be positive")
        self.connect = tuple(self.connect)
        if self.listen is not None:
            self.listen = tuple(self.listen)


def build_config(options: ZenohOptions | None = None) -> "zenoh.Config":  # noqa: F821
    """The ``zenoh.Config`` for ``options`` (safe embedded default when ``None``)."""
    import zenoh

    options = options or ZenohOptions()
    if options.config_file is not None:
        path = Path(options.config_file)
        try:
            config = zenoh.Config.from_json5(path.read_text(encoding="utf-8"))
        except OSError as exc:
            raise ValueError(f"{path}: cannot read the Zenoh configuration: {exc.strerror}") from None
        except zenoh.ZError as exc:
            raise ValueError(f"{path}: not a valid Zenoh JSON5 configuration: {exc}") from None
    else:
        config = zenoh.Config()
    default = zenoh.Config()

    def unset(key: str) -> bool:
        return config.get_json(key) == default.get_json(key)

    def put(key: str, value: Any, force: bool = False) -> None:
        if force or unset(key):
            config.insert_json5(key, json.dumps(value))

    file_sets_mode = options.config_file is not None and not unset("mode")
    put("mode", options.mode, force=not file_sets_mode)
    mode = json.loads(config.get_json("mode")) or options.mode
    config.insert_json5("scouting/multicast/enabled", "false")  # never scout the LAN
    put("scouting/gossip/enabled", options.gossip)
    if options.connect:
        put("connect/endpoints", list(options.connect), force=True)
    if options.listen is not None:
        put("listen/endpoints", list(options.listen), force=True)
    elif unset("listen/endpoints"):
        # A secured profile (TLS or QUIC links) gets no default listener: a plain tcp/ one on loopback
        # let any local process without a certificate connect and deliver (issue 22). Such an agent
        # connects out to its hub or router, and listens only where its file says (e.g. on tls/).
        plain_default = mode != "client" and not uses_secure_links(config)
        put("listen/endpoints", [loopback_endpoint()] if plain_default else [])
        if not plain_default and mode == "peer" and not file_sets_mode:
            # a peer without a listener reaches only the peers it links to itself; as a client, its
            # hub or router routes everything for it
            config.insert_json5("mode", json.dumps("client"))
    put("transport/link/tx/lease", options.lease_ms)
    put("transport/link/tx/keep_alive", options.keep_alive)
    put("transport/shared_memory/enabled", options.shared_memory)
    # One queue per link, not one per priority: Zenoh sends declarations (a liveliness token withdrawn: an agent
    # gone) at a higher priority than data, so with QoS on, an agent's leave overtook the messages it sent just
    # before (33 of 200 in tests/agents/test_transport_order.py); everything faultmas puts has one priority anyway.
    put("transport/unicast/qos/enabled", False)
    for key, value in options.extra.items():
        config.insert_json5(key, json.dumps(value))
    return config


def uses_secure_links(config: "zenoh.Config") -> bool:  # noqa: F821
    """Whether the configuration secures its links: TLS settings (certificates), or a ``tls/`` or ``quic/``
    listen endpoint. (Merely connecting to a ``tls/`` endpoint without a CA is not: that link fails.)"""
    endpoints = json.dumps(json.loads(config.get_json("listen/endpoints")))
    if '"tls/' in endpoints or '"quic/' in endpoints:
        return True
    tls = json.loads(config.get_json("transport/link/tls")) or {}
    return any(tls.get(key) for key in ("root_ca_certificate", "listen_certificate", "connect_certificate",
                                        "root_ca_certificate_base64", "listen_certificate_base64",
                                        "connect_certificate_base64", "enable_mtls"))


def listen_endpoints(config: "zenoh.Config") -> list[str]:  # noqa: F821
    """The endpoints a built config listens on (to tell other processes where to connect)."""
    value = json.loads(config.get_json("listen/endpoints"))
    if isinstance(value, dict):  # Zenoh's per-mode default form
        mode = json.loads(config.get_json("mode")) or "peer"
        value = value.get(mode, [])
    return list(value)
