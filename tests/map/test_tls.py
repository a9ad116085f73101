"""TLS: a ``rediss://`` map URL reaches a real TLS-only redis-server (a certificate made for the test),
with a password over it; without the certificate's CA, or with ``redis://``, one line and exit 2."""

from __future__ import annotations

import shutil
import subprocess
import time

import pytest

from _mapkit import free_port
from worldtrack.cli import main
from worldtrack.errors import InputError
from worldtrack.map.connection import connect

PASSWORD = "tls-Pa55"


@pytest.fixture(scope="module")
def tls_server(tmp_path_factory):
    pytest.importorskip("redis")
    exe, openssl = shutil.which("redis-server"), shutil.which("openssl")
    if exe is None or openssl is None:
        pytest.skip("redis-server or openssl is not installed (make test installs redis-server)")
    d = tmp_path_factory.mktemp("tls")
    subprocess.run([openssl, "req", "-x509", "-newkey", "rsa:2048", "-nodes", "-keyout", str(d / "key.pem"),
                    "-out", str(d / "cert.pem"), "-days", "2", "-subj", "/CN=127.0.0.1",
                    "-addext", "subjectAltName=IP:127.0.0.1"], check=True, capture_output=True)
    port = free_port()
    proc = subprocess.Popen([exe, "--port", "0", "--tls-port", str(port), "--bind", "127.0.0.1",
                             "--tls-cert-file", str(d / "cert.pem"), "--tls-key-file", str(d / "key.pem"),
                             "--tls-ca-cert-file", str(d / "cert.pem"), "--tls-auth-clients", "no",
                             "--requirepass", PASSWORD, "--save", "", "--appendonly", "no", "--dir", str(d)],
                            stdout=subprocess.DEVNULL, stderr=subprocess.DEVNULL)
    url = f"rediss://:{PASSWORD}@127.0.0.1:{port}/0?ssl_ca_certs={d / 'cert.pem'}"
    try:                                  # stopped however the set-up or the test ends
        deadline = time.monotonic() + 10
        while True:
            if proc.poll() is not None:
                pytest.skip("this redis-server was built without TLS")
            try:
                connect(url, timeout_s=1.0)
                break
            except InputError:
                if time.monotonic() > deadline:
                    raise
                time.sleep(0.05)
        yield url, port
    finally:
        proc.kill()
        proc.wait(5)


def test_rediss_reaches_a_tls_server_and_plain_or_unverified_connections_fail_in_one_line(tls_server, capsys):
    import redis
    url, port = tls_server
    client = connect(url)
    assert client.ping() and client.connection_pool.connection_class is redis.SSLConnection
    assert main(["map", "status", url]) == 0
    capsys.readouterr()
    assert main(["map", "status", f"rediss://:{PASSWORD}@127.0.0.1:{port}/0"]) == 2          # CA not given
    assert main(["map", "status", f"redis://:{PASSWORD}@127.0.0.1:{port}/0"]) == 2           # not TLS
    err = capsys.readouterr().err.strip().splitlines()
    assert len(err) == 2 and all(line.startswith(f"error: redis") for line in err)
    assert err[0].startswith(f"error: rediss://:***@127.0.0.1:{port}/0: cannot reach the map (")
    assert "certificate verify failed" in err[0]
    assert err[1].startswith(f"error: redis://:***@127.0.0.1:{port}/0: cannot reach the map (")
    assert all(PASSWORD not in line for line in err)
    with pytest.raises(InputError, match=r"^redis://:\*\*\*@127.0.0.1:\d+/0\?ssl_ca_certs=\S+: the redis client "
                                         r"takes no option 'ssl_ca_certs' \(TLS options such as ssl_ca_certs need "
                                         r"rediss://\)$"):
        connect(url.replace("rediss:", "redis:"))
