#!/usr/bin/env python3
"""A Sparkplug B host application written from the specification (Eclipse
Sparkplug 3.0.0) on python3-paho-mqtt and protoc's module of
proto/sparkplug_b/sparkplug_b.proto: it subscribes to a group's messages,
checks the rules an edge node must keep, and writes what it saw as JSON
(docs/sparkplug.md, tests/system/integration/test_sparkplug_stack.cpp).

Checked, each broken rule a line in "violations":
  - an edge node's first message of a session is NBIRTH, with seq 0 and a
    bdSeq metric; every later message of the session has the next seq
    (0-255, wrapping); NDEATH has the bdSeq of the NBIRTH it ends;
  - a device's DDATA and DDEATH come after its DBIRTH (in this session);
  - every metric of a birth has a name and a datatype; DDATA names only
    metrics of the device's birth.
Alarm transitions: every DDATA metric whose name ends in /A1, /A2 or
/Sensor Fault, with its value, timestamp, is_historical and the alarm id.
"""
import argparse
import json
import sys
import threading
import time

import paho.mqtt.client as mqtt

ALARM_SUFFIXES = ("/A1", "/A2", "/Sensor Fault")


def main():
    ap = argparse.ArgumentParser()
    ap.add_argument("--host", default="127.0.0.1")
    ap.add_argument("--port", type=int, required=True)
    ap.add_argument("--credentials", help="a file of 'username: U' and 'password: P' lines")
    ap.add_argument("--group", default="inspection")
    ap.add_argument("--tls", nargs=3, metavar=("CA", "CERT", "KEY"), help="TLS with the broker's CA and a client certificate")
    ap.add_argument("--pb-dir", required=True, help="where sparkplug_b/sparkplug_b_pb2.py is")
    ap.add_argument("--seconds", type=float, default=30.0, help="the most it runs")
    ap.add_argument("--until-ndeath", action="store_true", help="end at the first NDEATH")
    ap.add_argument("--rebirth-after", type=float, default=-1, help="send NCMD Node Control/Rebirth after this many s")
    ap.add_argument("--ready-file", help="written once subscribed")
    ap.add_argument("--dcmd", action="append", default=[],
                    help="DELAY_S:DEVICE:METRIC - send DCMD METRIC = true to DEVICE DELAY_S after the device's birth")
    ap.add_argument("--host-id", default="", help="be the primary host: STATE online (retained), its Will offline")
    ap.add_argument("--json", required=True)
    a = ap.parse_args()
    sys.path.insert(0, a.pb_dir)
    from sparkplug_b import sparkplug_b_pb2 as spb  # noqa: E402

    state = {"nodes": {}, "messages": 0, "by_type": {}, "violations": [], "alarms": [], "births": [],
             "node_births": 0, "ndeaths": 0, "ddeaths": 0, "ddata": 0, "last_seq": {}, "devices": {},
             "first_message_s": None, "rebirth_sent": False, "metrics_of": {}, "answers": [], "dcmd_sent": [],
             "dbirth_s": {}}
    done = threading.Event()
    t0 = time.monotonic()
    lock = threading.Lock()

    def violation(text):
        state["violations"].append(text)

    def on_message(client, userdata, msg):
        parts = msg.topic.split("/")
        if len(parts) < 4 or parts[0] != "spBv1.0":
            return
        kind, node = parts[2], parts[3]
        device = parts[4] if len(parts) > 4 else ""
        p = spb.Payload()
        try:
            p.ParseFromString(msg.payload)
        except Exception as e:  # noqa: BLE001
            violation(f"{msg.topic}: not a Sparkplug B payload: {e}")
            return
        with lock:
            state["messages"] += 1
            state["by_type"][kind] = state["by_type"].get(kind, 0) + 1
            if state["first_message_s"] is None:
                state["first_message_s"] = time.monotonic() - t0
            if kind in ("NCMD", "DCMD"):
                return  # a host's command (ours too): not the edge node's sequence
            n = state["nodes"].setdefault(node, {"born": False, "bdseq": None, "seq": None, "devices": {}})
            if kind == "NDEATH":
                state["ndeaths"] += 1
                bd = [m.long_value for m in p.metrics if m.name == "bdSeq"]
                state["births"].append({"type": "NDEATH", "bdseq": bd[0] if bd else None, "t_s": time.monotonic() - t0,
                                        "node_was_born": n["born"]})
                if not bd:
                    violation("NDEATH without bdSeq")
                elif n["bdseq"] is not None and bd[0] != n["bdseq"]:
                    violation(f"NDEATH bdSeq {bd[0]} != the NBIRTH's {n['bdseq']}")
                if p.HasField("seq"):
                    violation("NDEATH has a seq")
                n["born"] = False
                for d in n["devices"].values():
                    d["born"] = False
                if a.until_ndeath:
                    done.set()
                return
            if kind == "NBIRTH":
                state["node_births"] += 1
                bd = [m.long_value for m in p.metrics if m.name == "bdSeq"]
                if not bd:
                    violation("NBIRTH without bdSeq")
                if p.seq != 0:
                    violation(f"NBIRTH seq {p.seq} != 0")
                if not any(m.name == "Node Control/Rebirth" for m in p.metrics):
                    violation("NBIRTH without Node Control/Rebirth")
                n.update(born=True, bdseq=bd[0] if bd else None, seq=0)
                state["births"].append({"type": "NBIRTH", "bdseq": n["bdseq"], "t_s": time.monotonic() - t0})
                for d in n["devices"].values():
                    d["born"] = False
                return
            if not n["born"]:
                violation(f"{kind} {device} before the node's NBIRTH")
            elif not p.HasField("seq"):
                violation(f"{kind} {device} without seq")
            elif p.seq != (n["seq"] + 1) % 256:
                violation(f"{kind} {device}: seq {p.seq} after {n['seq']}")
            if p.HasField("seq"):
                n["seq"] = p.seq
            d = n["devices"].setdefault(device, {"born": False, "metrics": {}})
            if kind == "DBIRTH":
                d["born"] = True
                d["metrics"] = {}
                for m in p.metrics:
                    if not m.name or not m.HasField("datatype"):
                        violation(f"DBIRTH {device}: a metric without name or datatype")
                    d["metrics"][m.name] = m.datatype
                state["births"].append({"type": "DBIRTH", "device": device, "metrics": len(p.metrics),
                                        "t_s": time.monotonic() - t0})
                state["metrics_of"][device] = sorted(d["metrics"].keys())
                state["dbirth_s"].setdefault(device, time.monotonic() - t0)
                state["node_of"] = node
                return
            if not d["born"]:
                violation(f"{kind} {device} before its DBIRTH")
            if kind == "DDEATH":
                state["ddeaths"] += 1
                d["born"] = False
                return
            if kind != "DDATA":
                return
            state["ddata"] += 1
            ids = {m.name: m.long_value for m in p.metrics if m.name.endswith("/Alarm Id")}
            for m in p.metrics:
                if m.name == "Commands/Last Result":
                    state["answers"].append({"device": device, "text": m.string_value, "t_s": time.monotonic() - t0})
            for m in p.metrics:
                if m.name not in d["metrics"]:
                    violation(f"DDATA {device}: metric {m.name!r} not in its DBIRTH")
                if m.name.endswith(ALARM_SUFFIXES):
                    state["alarms"].append({
                        "device": device, "metric": m.name, "active": m.boolean_value,
                        "timestamp_ms": m.timestamp, "historical": m.is_historical,
                        "id": ids.get(m.name + "/Alarm Id", 0), "seq": p.seq,
                        "received_ms": int(time.time() * 1000)})

    def on_connect(client, userdata, flags, rc):
        if rc != 0:
            violation(f"the broker refused the host: rc {rc}")
            done.set()
            return
        client.subscribe(f"spBv1.0/{a.group}/#", qos=1)
        if a.host_id:  # section 7.4: after subscribing, online, retained
            client.publish(f"spBv1.0/STATE/{a.host_id}",
                           json.dumps({"online": True, "timestamp": int(time.time() * 1000)}), qos=1, retain=True)
        state["host_connects"] = state.get("host_connects", 0) + 1

    def on_subscribe(client, userdata, mid, granted):
        if a.ready_file:
            with open(a.ready_file, "w") as f:
                f.write("ready\n")

    client = mqtt.Client(client_id=f"sparkplug-host-{int(time.time() * 1000) % 100000}", clean_session=True)
    if a.credentials:
        creds = {}
        with open(a.credentials) as f:
            for line in f:
                if ":" in line:
                    k, v = line.split(":", 1)
                    creds[k.strip()] = v.strip().strip('"')
        client.username_pw_set(creds.get("username"), creds.get("password"))
    if a.tls:
        client.tls_set(ca_certs=a.tls[0], certfile=a.tls[1], keyfile=a.tls[2])
    if a.host_id:
        client.will_set(f"spBv1.0/STATE/{a.host_id}", json.dumps({"online": False, "timestamp": int(time.time() * 1000)}),
                        qos=1, retain=True)
    client.reconnect_delay_set(min_delay=0.2, max_delay=1)
    client.on_connect = on_connect
    client.on_message = on_message
    client.on_subscribe = on_subscribe
    deadline = t0 + a.seconds
    while True:  # the broker may be starting: a few tries, bounded by --seconds
        try:
            client.connect(a.host, a.port, keepalive=10)
            break
        except OSError:
            if time.monotonic() > deadline:
                print("sparkplug_host: cannot reach the broker", file=sys.stderr)
                return 2
            time.sleep(0.1)
    client.loop_start()
    while not done.is_set() and time.monotonic() < deadline:
        if a.rebirth_after >= 0 and not state["rebirth_sent"] and time.monotonic() - t0 >= a.rebirth_after:
            with lock:
                nodes = list(state["nodes"].keys())
            for node in nodes:
                p = spb.Payload()
                p.timestamp = int(time.time() * 1000)
                m = p.metrics.add()
                m.name = "Node Control/Rebirth"
                m.datatype = 11
                m.boolean_value = True
                client.publish(f"spBv1.0/{a.group}/NCMD/{node}", p.SerializeToString(), qos=0)
            state["rebirth_sent"] = bool(nodes)
        for spec in a.dcmd:
            delay, device, metric = spec.split(":", 2)
            with lock:
                born_s = state["dbirth_s"].get(device)
                node = state.get("node_of")
            if born_s is None or spec in state["dcmd_sent"] or time.monotonic() - t0 < born_s + float(delay):
                continue
            p = spb.Payload()
            p.timestamp = int(time.time() * 1000)
            m = p.metrics.add()
            m.name = metric
            m.datatype = 11
            m.boolean_value = True
            client.publish(f"spBv1.0/{a.group}/DCMD/{node}/{device}", p.SerializeToString(), qos=0)
            state["dcmd_sent"].append(spec)
        done.wait(0.05)
    client.loop_stop()
    client.disconnect()
    with lock:
        out = {k: v for k, v in state.items() if k not in ("nodes", "last_seq", "devices")}
    with open(a.json, "w") as f:
        json.dump(out, f, indent=1)
    print(f"sparkplug_host: {out['messages']} messages {out['by_type']}, {len(out['alarms'])} alarm transitions, "
          f"{len(out['violations'])} violations")
    for v in out["violations"][:20]:
        print("  violation:", v)
    return 0


if __name__ == "__main__":
    sys.exit(main())
