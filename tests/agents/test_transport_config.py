"""Zenoh configurations: the embedded default keeps everything on loopback; a security file wins."""
from __future__ import annotations

import json

import pytest

from agents.transport.config import ZenohOptions, build_config, listen_endpoints


def value(config, key):
    return json.loads(config.get_json(key))


def test_embedded_default_is_a_loopback_peer_without_multicast():
    config = build_config()
    assert value(config, "mode") == "peer"
    assert value(config, "scouting/multicast/enabled") is False
    [endpoint] = listen_endpoints(config)
    assert endpoint.startswith("tcp/127.0.0.1:") and int(endpoint.rsplit(":", 1)[1]) > 0
    assert value(config, "transport/shared_memory/enabled") is False
    assert value(config, "transport/link/tx/lease") == 1000
    assert value(config, "transport/link/tx/keep_alive") == 4


def test_client_listens_nowhere_and_connects_where_told():
    config = build_config(ZenohOptions(mode="client", connect=("tcp/127.0.0.1:7447",)))
    assert listen_endpoints(config) == []
    assert value(config, "connect/endpoints") == ["tcp/127.0.0.1:7447"]


def test_a_config_file_wins_where_it_sets_a_key_but_never_enables_multicast(tmp_path):
    path = tmp_path / "zenoh.json5"
    path.write_text("""{
      // deployment file: TLS listener and a longer lease
      listen: { endpoints: ["tls/localhost:7447"] },
      scouting: { multicast: { enabled: true } },
      transport: { link: { tx: { lease: 3000 } } },
      access_control: { enabled: true, default_permission: "allow" },
    }""")
    config = build_config(ZenohOptions(config_file=path))
    assert listen_endpoints(config) == ["tls/localhost:7447"]
    assert value(config, "transport/link/tx/lease") == 3000
    assert value(config, "transport/link/tx/keep_alive") == 4
    assert value(config, "access_control/enabled") is True
    assert value(config, "scouting/multicast/enabled") is False


def test_bad_config_file_names_the_file(tmp_path):
    path = tmp_path / "broken.json5"
    path.write_text("{ mode: ")
    with pytest.raises(ValueError, match="broken.json5"):
        build_config(ZenohOptions(config_file=path))
    with pytest.raises(ValueError, match="missing.json5"):
        build_config(ZenohOptions(config_file=tmp_path / "missing.json5"))


def test_unknown_mode_is_refused():
    with pytest.raises(ValueError, match="'server'"):
        ZenohOptions(mode="server")
