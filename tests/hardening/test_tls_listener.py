"""Issue 22, found item 6: the documented TLS profile left a plain-TCP listener on loopback, through
which a local client without a certificate delivered a tell. With real Zenoh sessions: an agent of the
TLS profile opens no listening socket of its own, and two such agents still talk through the TLS hub."""
from __future__ import annotations

import shutil

import psutil
import pytest
import zenoh

from agents.transport import Envelope, Inbox, ZenohOptions, ZenohTransport, free_port
from tests.agents.test_transport_security import make_certificates
from tests.agents.transport_fixtures import unique_mas


def listening_ports() -> set[int]:
    return {c.laddr.port for c in psutil.Process().net_connections(kind="inet")
            if c.status == psutil.CONN_LISTEN}


@pytest.mark.skipif(shutil.which("openssl") is None, reason="needs the openssl command to make certificates")
def test_agents_of_the_tls_profile_listen_on_nothing_plain_and_still_talk(tmp_path):
    files = make_certificates(tmp_path)
    hub_file, agent_file = tmp_path / "hub.json5", tmp_path / "agent.json5"
    hub_file.write_text(f'{{ transport: {{ link: {{ tls: {{ listen_certificate: "{files["hub.pem"]}", '
                        f'listen_private_key: "{files["hub.key"]}" }} }} }} }}')
    agent_file.write_text(f'{{ transport: {{ link: {{ tls: {{ root_ca_certificate: "{files["ca.pem"]}" }} }} }} }}')
    endpoint, mas = f"tls/localhost:{free_port()}", unique_mas()
    before = listening_ports()
    with ZenohTransport(mas, ZenohOptions(mode="router", listen=(endpoint,), config_file=hub_file)) as hub:
        hub_ports = listening_ports() - before
        with ZenohTransport(mas, ZenohOptions(connect=(endpoint,), config_file=agent_file)) as alice_side, \
                ZenohTransport(mas, ZenohOptions(connect=(endpoint,), config_file=agent_file)) as bob_side:
            assert listening_ports() - before == hub_ports  # the agents added no listener
            inbox = Inbox()
            alice_side.register("alice", Inbox())
            bob_side.register("bob", inbox)
            assert alice_side.wait_for_agents(["bob"], timeout=10)
            assert alice_side.send(Envelope(mas, "alice", ("bob",), "tell", "agent_to_agent")) == ()
            assert inbox.get(timeout=10).content == "agent_to_agent"
            # a local client without TLS tries every port this process listens on: no way in
            for port in listening_ports() - before:
                plain = ZenohTransport(mas, ZenohOptions(mode="client", connect=(f"tcp/127.0.0.1:{port}",)))
                try:
                    plain.open()
                except zenoh.ZError:
                    continue  # no session at all: refused
                with plain:
                    assert not plain.wait_for_agents(["bob"], timeout=1.0)
                    assert plain.send(Envelope(mas, "mallory", ("bob",), "tell", "sneaked_in")) == ("bob",)
            assert inbox.get(timeout=0.5) is None
