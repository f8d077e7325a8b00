#!/usr/bin/python3
"""End-to-end: what tools and operators expect of a gRPC service, against a real cenote-server.

- the standard health service answers SERVING (grpc.health.v1, as Kubernetes probes and
  grpc_health_probe call it);
- server reflection lists cenote's services (what grpcurl uses);
- TLS: a client trusting the server's CA gets in, a plain-text client does not; with a client CA
  (mutual TLS) a client without a certificate is refused, one with a signed certificate gets in;
  the bearer token is still checked over TLS; the live viewer's port takes the server's certificate:
  its page and its WebSocket (token checked) over TLS from Python's ssl, a plain connection dropped;
- keepalive: a subscriber whose process stops answering (SIGSTOP: its TCP connection stays open, a
  half-open tether link) is dropped by the server's keepalive pings, and its subscription ends;
- the token is checked before the request is parsed: a body that is not a protobuf message, or one
  of 60 MiB, gets UNAUTHENTICATED without a token (a parsed one would be INTERNAL), and the
  read-only token gets PERMISSION_DENIED for Admin.Reset, also unparsed.
Calls are made with raw bytes (grpcio's generic calls), so no generated stubs are needed.
Usage: server_protocols_test.py <cenote-server binary>
"""
import json
import os
import re
import shutil
import signal
import socket
import ssl
import subprocess
import sys
import tempfile
import time
import unittest

import grpc

SERVER = sys.argv.pop(1) if len(sys.argv) > 1 else os.environ.get("CENOTE_SERVER_BINARY", "")

HEALTH_CHECK = "/grpc.health.v1.Health/Check"
REFLECTION = "/grpc.reflection.v1alpha.ServerReflection/ServerReflectionInfo"
MAP_INFO = "/cenote.v1.Query/GetMapInfo"
INTEGRATE = "/cenote.v1.Ingest/IntegratePoints"
RESET = "/cenote.v1.Admin/Reset"
NOT_PROTOBUF = b"\xff\xff\xff\xff"  # field 0 with a truncated varint: no message parses from it
SERVING = b"\x08\x01"  # HealthCheckResponse{status: SERVING}
LIST_SERVICES = b"\x3a\x01*"  # ServerReflectionRequest{list_services: "*"}


def identity(x):
    return x


class Server:
    """cenote-server on a free loopback port, in a directory of its own."""

    def __init__(self, workdir, *args):
        self.port_file = os.path.join(workdir, "port")
        if os.path.exists(self.port_file):
            os.remove(self.port_file)
        self.log = open(os.path.join(workdir, "server.log"), "w")
        self.process = subprocess.Popen(
            [SERVER, "--listen", "127.0.0.1:0", "--port-file", self.port_file,
             "--snapshot-dir", os.path.join(workdir, "snapshots"), *args],
            stdout=self.log, stderr=subprocess.STDOUT)
        deadline = time.time() + 60
        while not os.path.exists(self.port_file):
            if self.process.poll() is not None or time.time() > deadline:
                raise RuntimeError("cenote-server did not start: " + open(self.log.name).read())
            time.sleep(0.05)
        self.target = "localhost:" + read(self.port_file).decode().strip()

    def stop(self):
        self.process.send_signal(signal.SIGTERM)
        code = self.process.wait(timeout=60)
        self.log.close()
        return code


def unary(channel, method, request=b"", metadata=None):
    call = channel.unary_unary(method, request_serializer=identity, response_deserializer=identity)
    return call(request, timeout=10, metadata=metadata)


def openssl(*args):
    subprocess.run(["openssl", *args], check=True, capture_output=True)


def make_certificates(d):
    """A CA, a server certificate for localhost and a client certificate, all signed by the CA."""
    openssl("req", "-x509", "-newkey", "rsa:2048", "-nodes", "-days", "2", "-subj", "/CN=cenote test CA",
            "-keyout", f"{d}/ca.key", "-out", f"{d}/ca.pem")
    for name in ("server", "client"):
        openssl("req", "-newkey", "rsa:2048", "-nodes", "-subj", "/CN=localhost", "-keyout", f"{d}/{name}.key",
                "-out", f"{d}/{name}.csr")
        with open(f"{d}/{name}.ext", "w") as ext:
            ext.write("subjectAltName=DNS:localhost,IP:127.0.0.1\n")
        openssl("x509", "-req", "-in", f"{d}/{name}.csr", "-CA", f"{d}/ca.pem", "-CAkey", f"{d}/ca.key",
                "-CAcreateserial", "-days", "2", "-extfile", f"{d}/{name}.ext", "-out", f"{d}/{name}.pem")


def read(path):
    with open(path, "rb") as f:
        return f.read()


class ScratchDirTest(unittest.TestCase):
    """Each test gets a fresh folder of its own, self.dir (named after `prefix`), removed after it."""
    prefix = "cenote-"

    def setUp(self):
        self.dir = tempfile.mkdtemp(prefix=self.prefix)
        self.addCleanup(shutil.rmtree, self.dir)


class StandardServices(ScratchDirTest):
    prefix = "cenote-protocols-"

    def test_health_reports_serving_and_reflection_lists_the_services(self):
        server = Server(self.dir)
        with grpc.insecure_channel(server.target) as channel:
            self.assertEqual(unary(channel, HEALTH_CHECK), SERVING)
            stream = channel.stream_stream(REFLECTION, request_serializer=identity, response_deserializer=identity)
            reply = next(iter(stream(iter([LIST_SERVICES]), timeout=10)))
            for service in (b"cenote.v1.Ingest", b"cenote.v1.Query", b"cenote.v1.Updates", b"cenote.v1.Admin"):
                self.assertIn(service, reply)
        self.assertEqual(server.stop(), 0)


class Tls(unittest.TestCase):
    @classmethod
    def setUpClass(cls):
        cls.dir = tempfile.mkdtemp(prefix="cenote-tls-")
        make_certificates(cls.dir)

    @classmethod
    def tearDownClass(cls):
        shutil.rmtree(cls.dir)

    def test_tls_with_token(self):
        with open(f"{self.dir}/token", "w") as f:
            f.write("s3cret\n")
        server = Server(self.dir, "--tls-cert", f"{self.dir}/server.pem", "--tls-key", f"{self.dir}/server.key",
                        "--token-file", f"{self.dir}/token")
        trusted = grpc.ssl_channel_credentials(root_certificates=read(f"{self.dir}/ca.pem"))
        with grpc.secure_channel(server.target, trusted) as channel:
            unary(channel, MAP_INFO, metadata=[("authorization", "Bearer s3cret")])
            with self.assertRaises(grpc.RpcError) as wrong:
                unary(channel, MAP_INFO, metadata=[("authorization", "Bearer guess")])
            self.assertEqual(wrong.exception.code(), grpc.StatusCode.UNAUTHENTICATED)
        with grpc.insecure_channel(server.target) as plain:
            with self.assertRaises(grpc.RpcError) as refused:
                unary(plain, MAP_INFO, metadata=[("authorization", "Bearer s3cret")])
            self.assertEqual(refused.exception.code(), grpc.StatusCode.UNAVAILABLE)
        self.assertEqual(server.stop(), 0)

    def test_mutual_tls_needs_a_client_certificate_signed_by_the_ca(self):
        server = Server(self.dir, "--tls-cert", f"{self.dir}/server.pem", "--tls-key", f"{self.dir}/server.key",
                        "--tls-client-ca", f"{self.dir}/ca.pem")
        anonymous = grpc.ssl_channel_credentials(root_certificates=read(f"{self.dir}/ca.pem"))
        with grpc.secure_channel(server.target, anonymous) as channel:
            with self.assertRaises(grpc.RpcError) as refused:
                unary(channel, MAP_INFO)
            self.assertEqual(refused.exception.code(), grpc.StatusCode.UNAVAILABLE)
        signed = grpc.ssl_channel_credentials(root_certificates=read(f"{self.dir}/ca.pem"),
                                              private_key=read(f"{self.dir}/client.key"),
                                              certificate_chain=read(f"{self.dir}/client.pem"))
        with grpc.secure_channel(server.target, signed) as channel:
            unary(channel, MAP_INFO)
        self.assertEqual(server.stop(), 0)

    def test_the_viewer_port_serves_only_tls_with_the_servers_certificate(self):
        with open(f"{self.dir}/token", "w") as f:
            f.write("s3cret\n")
        server = Server(self.dir, "--tls-cert", f"{self.dir}/server.pem", "--tls-key", f"{self.dir}/server.key",
                        "--token-file", f"{self.dir}/token", "--viewer-listen", "127.0.0.1:0")
        match = re.search(r"viewer on https://127\.0\.0\.1:(\d+)/ \(Foxglove: wss://127\.0\.0\.1:\1\)",
                          read(server.log.name).decode())
        self.assertIsNotNone(match, read(server.log.name))
        port = int(match.group(1))
        trusted = ssl.create_default_context(cafile=f"{self.dir}/ca.pem")

        def exchange(request, context=trusted):
            """What the viewer answers to `request` over TLS: the bytes until it closes or 2 s pass."""
            with socket.create_connection(("127.0.0.1", port), timeout=10) as raw:
                with context.wrap_socket(raw, server_hostname="localhost") as tls:
                    tls.sendall(request)
                    tls.settimeout(2.0)
                    reply = b""
                    try:
                        while chunk := tls.recv(65536):
                            reply += chunk
                    except (socket.timeout, ssl.SSLError):
                        pass
                    return reply

        upgrade = ("GET /{} HTTP/1.1\r\nHost: localhost\r\nUpgrade: websocket\r\nConnection: Upgrade\r\n"
                   "Sec-WebSocket-Key: dGhlIHNhbXBsZSBub25jZQ==\r\nSec-WebSocket-Version: 13\r\n"
                   "Sec-WebSocket-Protocol: foxglove.websocket.v1\r\n\r\n")
        page = exchange(b"GET /no-such-file HTTP/1.1\r\nHost: localhost\r\nConnection: close\r\n\r\n")
        self.assertTrue(page.startswith(b"HTTP/1.1 404 "), page[:200])
        self.assertIn(b"no such file: /no-such-file", page)
        self.assertTrue(exchange(upgrade.format("").encode()).startswith(b"HTTP/1.1 401 "))
        accepted = exchange(upgrade.format("?token=s3cret").encode())
        head, _, frames = accepted.partition(b"\r\n\r\n")
        self.assertTrue(head.startswith(b"HTTP/1.1 101 "), head)
        self.assertIn(b"Sec-WebSocket-Protocol: foxglove.websocket.v1", head)
        # The first WebSocket frame: text (0x81), the server's serverInfo.
        self.assertEqual(frames[0], 0x81)
        length, offset = frames[1] & 0x7F, 2
        if length == 126:
            length, offset = int.from_bytes(frames[2:4], "big"), 4
        self.assertEqual(json.loads(frames[offset:offset + length])["op"], "serverInfo")
        # A client that does not trust the certificate, and one that does not speak TLS, get nothing.
        with self.assertRaises(ssl.SSLCertVerificationError):
            exchange(upgrade.format("?token=s3cret").encode(), ssl.create_default_context())
        with socket.create_connection(("127.0.0.1", port), timeout=10) as plain:
            plain.sendall(b"GET / HTTP/1.1\r\nHost: localhost\r\n\r\n")
            plain.settimeout(10.0)
            try:
                answer = plain.recv(65536)
            except ConnectionResetError:
                answer = b""
            self.assertFalse(answer.startswith(b"HTTP/"), answer[:200])
        self.assertEqual(server.stop(), 0)


STATS = "/cenote.v1.Admin/GetStats"
SUBSCRIBER = '''
import sys, grpc
channel = grpc.insecure_channel(sys.argv[1])
call = channel.unary_stream("/cenote.v1.Updates/Subscribe", request_serializer=lambda x: x,
                            response_deserializer=lambda x: x)(b"", timeout=600)
next(call)
print("subscribed", flush=True)
for _ in call:
    pass
'''


def varint_field(message, number):
    """The value of varint field `number` in a serialised protobuf message (0 when absent)."""
    def varint(i):
        value, shift = 0, 0
        while True:
            b = message[i]
            value |= (b & 0x7F) << shift
            i, shift = i + 1, shift + 7
            if b < 0x80:
                return value, i
    i, found = 0, 0
    while i < len(message):
        key, i = varint(i)
        wire = key & 7
        if wire == 0:
            value, i = varint(i)
            if key >> 3 == number:
                found = value
        elif wire == 1:
            i += 8
        elif wire == 2:
            length, i = varint(i)
            i += length
        elif wire == 5:
            i += 4
        else:
            raise ValueError(f"wire type {wire}")
    return found


class Keepalive(ScratchDirTest):
    prefix = "cenote-keepalive-"

    def test_a_subscriber_that_stops_answering_is_dropped(self):
        with open(f"{self.dir}/config.yaml", "w") as f:
            f.write("server:\n  transport:\n    keepalive_time_s: 1\n    keepalive_timeout_s: 1\n")
        server = Server(self.dir, "--config", f"{self.dir}/config.yaml")
        subscriber = subprocess.Popen([sys.executable, "-c", SUBSCRIBER, server.target], stdout=subprocess.PIPE)
        try:
            self.assertEqual(subscriber.stdout.readline().strip(), b"subscribed")
            with grpc.insecure_channel(server.target) as channel:
                self.assertEqual(varint_field(unary(channel, STATS), 15), 1)  # Stats.subscribers
                os.kill(subscriber.pid, signal.SIGSTOP)  # its kernel keeps the connection; gRPC answers nothing
                subscribers = 1
                for _ in range(300):  # 30 s at most; keepalive needs about 2
                    subscribers = varint_field(unary(channel, STATS), 15)
                    if subscribers == 0:
                        break
                    time.sleep(0.1)
                self.assertEqual(subscribers, 0)
        finally:
            subscriber.kill()
            subscriber.wait()
        self.assertEqual(server.stop(), 0)


class TokenBeforeParsing(ScratchDirTest):
    prefix = "cenote-token-"

    def setUp(self):
        super().setUp()
        for name, token in (("operator", "op-secret"), ("planner", "planner-secret")):
            with open(f"{self.dir}/{name}", "w") as f:
                f.write(token + "\n")

    def code(self, channel, method, body, token=None):
        metadata = [("authorization", f"Bearer {token}")] if token else None
        with self.assertRaises(grpc.RpcError) as refused:
            unary(channel, method, body, metadata=metadata)
        return refused.exception.code(), refused.exception.details()

    def test_a_call_without_the_token_is_refused_before_its_message_is_parsed(self):
        server = Server(self.dir, "--token-file", f"{self.dir}/operator", "--read-token-file", f"{self.dir}/planner")
        with grpc.insecure_channel(server.target) as channel:
            missing = (grpc.StatusCode.UNAUTHENTICATED, "missing token: send metadata 'authorization: Bearer <token>'")
            self.assertEqual(self.code(channel, INTEGRATE, NOT_PROTOBUF), missing)
            self.assertEqual(self.code(channel, INTEGRATE, NOT_PROTOBUF, token="guess"),
                             (grpc.StatusCode.UNAUTHENTICATED, "wrong token"))
            self.assertEqual(self.code(channel, RESET, NOT_PROTOBUF, token="planner-secret")[0],
                             grpc.StatusCode.PERMISSION_DENIED)
            # 60 MiB that claim to be one huge field: never read into a message.
            self.assertEqual(self.code(channel, INTEGRATE, b"\x0a\x80\x80\x80\x1e" + bytes(60 << 20)), missing)
            # With the operator's token the same bytes reach the parser, which refuses them.
            self.assertEqual(self.code(channel, INTEGRATE, NOT_PROTOBUF, token="op-secret")[0],
                             grpc.StatusCode.INTERNAL)
        self.assertEqual(server.stop(), 0)


if __name__ == "__main__":
    unittest.main(verbosity=2)
