#!/usr/bin/env python3
"""A robot written from proto/ alone, in Python, as a user of the link would.

It speaks docs/link-protocol.md to a real pc_server: mutual TLS, delimited
Envelopes (a base-128 varint length, then the bytes), Hello, then telemetry at
20 Hz and heartbeats, acknowledging commands it cannot carry out as REJECTED.
Its telemetry carries the pose and the mode only, and leaves every optional
field out (link protocol 2, "Presence"): the server must show those as
unknown, never as 0. With --send-zeros it sends them, all 0, instead.

The module comes from protoc, not from this project's C++:
  protoc --python_out=DIR -I proto proto/inspect_robot/v1/link.proto
(the build does it: <build>/python_proto).

  python_robot.py --port N --certs DIR [--id robot1] [--seconds 5]
                  [--protocol-version 2] [--send-zeros] --pb-dir DIR

Exit: 0 after --seconds of telemetry; 3 when the server refused the Hello
(its reason on stdout); 2 on a connection or protocol error.
"""
import argparse
import select
import socket
import ssl
import sys
import time


def varint(n):
    out = bytearray()
    while True:
        b = n & 0x7F
        n >>= 7
        if n:
            out.append(b | 0x80)
        else:
            out.append(b)
            return bytes(out)


class Link:
    """Delimited Envelopes over a TLS socket."""

    def __init__(self, sock, pb):
        self.sock = sock
        self.pb = pb
        self.seq = 0
        self.buf = b""

    def send(self, **body):
        self.seq += 1
        env = self.pb.Envelope(seq=self.seq, send_time_us=int(time.monotonic() * 1e6), **body)
        data = env.SerializeToString()
        self.sock.sendall(varint(len(data)) + data)

    def _frame(self):
        """One Envelope from the buffer, or None when it holds no whole one."""
        n, shift, i = 0, 0, 0
        while True:
            if i >= len(self.buf):
                return None
            b = self.buf[i]
            n |= (b & 0x7F) << shift
            i += 1
            if not b & 0x80:
                break
            shift += 7
            if shift > 63:
                raise ValueError("length varint longer than 10 bytes")
        if n > 1 << 20:
            raise ValueError(f"frame of {n} bytes is above 1 MiB")
        if len(self.buf) < i + n:
            return None
        env = self.pb.Envelope()
        env.ParseFromString(self.buf[i:i + n])
        self.buf = self.buf[i + n:]
        return env

    def receive(self, timeout_s):
        """Envelopes that arrived within timeout_s (at least one wait)."""
        out = []
        deadline = time.monotonic() + timeout_s
        while True:
            env = self._frame()
            if env is not None:
                out.append(env)
                continue
            left = deadline - time.monotonic()
            if out or left <= 0:
                return out
            if not self.sock.pending():
                ready, _, _ = select.select([self.sock], [], [], left)
                if not ready:
                    return out
            chunk = self.sock.recv(65536)
            if not chunk:
                raise ConnectionError("the server closed the connection")
            self.buf += chunk


def main():
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--host", default="127.0.0.1")
    ap.add_argument("--port", type=int, required=True)
    ap.add_argument("--certs", required=True, help="folder with ca.pem and <id>.pem/.key (scripts/make_certs.sh)")
    ap.add_argument("--id", default="robot1")
    ap.add_argument("--seconds", type=float, default=5.0)
    ap.add_argument("--protocol-version", type=int, default=2)
    ap.add_argument("--send-zeros", action="store_true", help="send the optional fields, all 0")
    ap.add_argument("--pb-dir", required=True, help="where protoc --python_out wrote inspect_robot/")
    args = ap.parse_args()
    if not 0 < args.seconds <= 600:
        ap.error("--seconds must be in (0, 600]")

    sys.path.insert(0, args.pb_dir)
    from inspect_robot.v1 import link_pb2 as pb  # noqa: E402 (generated at build time)

    ctx = ssl.SSLContext(ssl.PROTOCOL_TLS_CLIENT)
    ctx.minimum_version = ssl.TLSVersion.TLSv1_2
    ctx.load_verify_locations(f"{args.certs}/ca.pem")
    ctx.load_cert_chain(f"{args.certs}/{args.id}.pem", f"{args.certs}/{args.id}.key")
    try:
        raw = socket.create_connection((args.host, args.port), timeout=5)
        sock = ctx.wrap_socket(raw, server_hostname=args.host)
    except (OSError, ssl.SSLError) as e:
        print(f"python_robot: cannot connect to {args.host}:{args.port}: {e}")
        return 2
    link = Link(sock, pb)
    link.send(hello=pb.Hello(robot_id=args.id, protocol_version=args.protocol_version,
                             capabilities=["teleop"], software_version="python_robot"))
    reply = None
    for _ in range(50):  # 5 s at most
        for env in link.receive(0.1):
            if env.WhichOneof("body") == "hello_reply":
                reply = env.hello_reply
        if reply is not None:
            break
    if reply is None:
        print("python_robot: no HelloReply within 5 s")
        return 2
    print(f"python_robot: hello_reply accepted={reply.accepted} protocol_version={reply.protocol_version} "
          f"reason={reply.reason!r}", flush=True)
    if not reply.accepted:
        return 3

    t0 = time.monotonic()
    sent = 0
    while time.monotonic() - t0 < args.seconds:
        t = pb.Telemetry(robot_time_us=int((time.monotonic() - t0) * 1e6), mode=pb.IDLE)
        t.pose.x_m, t.pose.y_m, t.pose.theta_rad = 1.0, 2.0, 0.5
        if args.send_zeros:
            for f in t.DESCRIPTOR.fields:
                if f.has_presence and f.type in (f.TYPE_DOUBLE, f.TYPE_UINT32, f.TYPE_UINT64) \
                        and f.label != f.LABEL_REPEATED:
                    setattr(t, f.name, 0)
        link.send(telemetry=t)
        link.send(heartbeat=pb.Heartbeat(time_us=int(time.monotonic() * 1e6)))
        sent += 1
        for env in link.receive(0.05):
            if env.WhichOneof("body") == "command":
                link.send(ack=pb.Ack(command_id=env.command.id, status=pb.Ack.REJECTED,
                                     reason="python_robot: a test robot, it does not move"))
    print(f"python_robot: sent {sent} telemetry messages", flush=True)
    sock.close()
    return 0


if __name__ == "__main__":
    sys.exit(main())
