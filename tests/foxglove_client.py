"""A small client of the Foxglove WebSocket protocol (foxglove.websocket.v1),
written from the protocol's specification with the `websockets` package, so
the tests check `physics-node --foxglove` with code independent of the SDK
that serves it. Holds no tests itself.

foxglove-sdk servers accept only the subprotocol name `foxglove.sdk.v1`, the
same protocol as `foxglove.websocket.v1` under a new name; the client offers
both, as current Foxglove apps do.

Server -> client: JSON text (serverInfo, advertise, advertiseServices,
status, ...) and binary frames whose first byte is the opcode: 1 message
data (subscription id u32, log time u64, payload), 2 time (u64 ns), 3
service call response (service id u32, call id u32, encoding length u32,
encoding, payload). Client -> server: JSON subscribe, and binary opcode 2
service call request (service id u32, call id u32, encoding length u32,
encoding, payload). Integers are little-endian.
"""

import base64
import json
import struct
import time

from google.protobuf import descriptor_pb2, descriptor_pool, message_factory
from websockets.sync.client import connect

SUBPROTOCOLS = ["foxglove.sdk.v1", "foxglove.websocket.v1"]
OP_MESSAGE_DATA, OP_TIME, OP_SERVICE_RESPONSE = 1, 2, 3
OP_SERVICE_REQUEST = 2


class FoxgloveClient:
    def __init__(self, url, timeout=10.0):
        self._connection = connect(url, subprotocols=SUBPROTOCOLS, open_timeout=timeout, max_size=None)
        self.ws = self._connection.__enter__()
        self.server_info = None
        self.channels = {}  # topic -> advertised channel (dict)
        self.services = {}  # name -> advertised service (dict)
        self.times = []  # server time messages, ns
        self.messages = {}  # subscription id -> [(log time ns, payload bytes)]
        self.responses = {}  # call id -> (encoding, payload)
        self._subscriptions = {}
        self._next_id = 1

    def close(self):
        self._connection.__exit__(None, None, None)

    def __enter__(self):
        return self

    def __exit__(self, *exc):
        self.close()

    def _receive(self, timeout):
        try:
            frame = self.ws.recv(timeout=timeout)
        except TimeoutError:
            return
        if isinstance(frame, str):
            msg = json.loads(frame)
            op = msg.get("op")
            if op == "serverInfo":
                self.server_info = msg
            elif op == "advertise":
                for ch in msg["channels"]:
                    self.channels[ch["topic"]] = ch
            elif op == "advertiseServices":
                for s in msg["services"]:
                    self.services[s["name"]] = s
            return
        op = frame[0]
        if op == OP_MESSAGE_DATA:
            sub, log_time = struct.unpack_from("<IQ", frame, 1)
            self.messages.setdefault(sub, []).append((log_time, bytes(frame[13:])))
        elif op == OP_TIME:
            self.times.append(struct.unpack_from("<Q", frame, 1)[0])
        elif op == OP_SERVICE_RESPONSE:
            _service, call, n = struct.unpack_from("<III", frame, 1)
            encoding = bytes(frame[13 : 13 + n]).decode()
            self.responses[call] = (encoding, bytes(frame[13 + n :]))

    def pump_until(self, predicate, timeout=10.0, what="condition"):
        deadline = time.monotonic() + timeout
        while not predicate():
            left = deadline - time.monotonic()
            if left <= 0:
                raise AssertionError(f"timed out waiting for {what}")
            self._receive(min(left, 0.2))

    def pump(self, seconds):
        """Take in whatever the server sends for `seconds`."""
        deadline = time.monotonic() + seconds
        while (left := deadline - time.monotonic()) > 0:
            self._receive(left)

    def subscribe(self, topic, timeout=10.0):
        self.pump_until(lambda: topic in self.channels, timeout, f"channel {topic} to be advertised")
        sub = self._next_id
        self._next_id += 1
        subscription = {"id": sub, "channelId": self.channels[topic]["id"]}
        self.ws.send(json.dumps({"op": "subscribe", "subscriptions": [subscription]}))
        self._subscriptions[topic] = sub
        self.messages[sub] = []
        return sub

    def received(self, topic):
        return self.messages.get(self._subscriptions[topic], [])

    def call(self, name, request=b"{}", encoding="json", timeout=10.0):
        self.pump_until(lambda: name in self.services, timeout, f"service {name} to be advertised")
        call_id = self._next_id
        self._next_id += 1
        enc = encoding.encode()
        frame = struct.pack("<BIII", OP_SERVICE_REQUEST, self.services[name]["id"], call_id, len(enc)) + enc + request
        self.ws.send(frame)
        self.pump_until(lambda: call_id in self.responses, timeout, f"the answer of {name}")
        encoding, payload = self.responses.pop(call_id)
        return json.loads(payload) if encoding == "json" else payload


def protobuf_class(channel):
    """The message class of a protobuf channel, built from the FileDescriptorSet it advertised."""
    assert channel["schemaEncoding"] == "protobuf", channel
    files = descriptor_pb2.FileDescriptorSet.FromString(base64.b64decode(channel["schema"]))
    pool = descriptor_pool.DescriptorPool()
    for f in files.file:
        pool.Add(f)
    return message_factory.GetMessageClass(pool.FindMessageTypeByName(channel["schemaName"]))
