#!/usr/bin/env python3
"""A third-party MQTT consumer for the publishing tests (tests/daemon/hil_mqtt_test.cpp).

Debian's python3-paho-mqtt, MQTT v5, a persistent session (clean_start False, session expiry
one hour) with a QoS 1 subscription to PREFIX/#, as a historian would run it: a broker that
restarts with its persistence keeps the session and queues what is published meanwhile.
Prints one JSON object per line on stdout (flushed):
  {"event": "subscribed"}                                  after each SUBACK
  {"topic": ..., "t": unix time, "retain": bool, "props": {user properties},
   "size": payload bytes, "text": the payload (JSON and status topics only)}
Runs until killed.
"""
import argparse
import json
import sys
import time

import paho.mqtt.client as mqtt
from paho.mqtt.packettypes import PacketTypes
from paho.mqtt.properties import Properties


def emit(obj):
    sys.stdout.write(json.dumps(obj, separators=(",", ":")) + "\n")
    sys.stdout.flush()


def main():
    parser = argparse.ArgumentParser()
    parser.add_argument("--host", default="127.0.0.1")
    parser.add_argument("--port", type=int, required=True)
    parser.add_argument("--prefix", required=True, help="subscribes to PREFIX/#")
    parser.add_argument("--client-id", default="springscan-test-subscriber")
    parser.add_argument("--ca-file", help="TLS: the CA of the broker's certificate")
    args = parser.parse_args()

    client = mqtt.Client(client_id=args.client_id, protocol=mqtt.MQTTv5)
    if args.ca_file:
        client.tls_set(ca_certs=args.ca_file)
    client.reconnect_delay_set(min_delay=1, max_delay=1)

    def on_connect(c, userdata, flags, reason_code, properties):
        emit({"event": "connected", "session_present": bool(flags.get("session present"))})
        c.subscribe(args.prefix + "/#", qos=1)

    def on_subscribe(c, userdata, mid, reason_codes, properties):
        emit({"event": "subscribed"})

    def on_message(c, userdata, message):
        props = {}
        user = getattr(message.properties, "UserProperty", None) if message.properties else None
        for name, value in user or []:
            props[name] = value
        record = {
            "topic": message.topic,
            "t": time.time(),
            "retain": bool(message.retain),
            "props": props,
            "size": len(message.payload),
        }
        if not message.topic.endswith("/result"):
            record["text"] = message.payload.decode("utf-8", "replace")
        emit(record)

    client.on_connect = on_connect
    client.on_subscribe = on_subscribe
    client.on_message = on_message
    connect_props = Properties(PacketTypes.CONNECT)
    connect_props.SessionExpiryInterval = 3600
    while True:
        try:
            client.connect(args.host, args.port, keepalive=10, clean_start=False,
                           properties=connect_props)
            break
        except OSError:
            time.sleep(0.2)
    client.loop_forever(retry_first_connection=True)


if __name__ == "__main__":
    main()
