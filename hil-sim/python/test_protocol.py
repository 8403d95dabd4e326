"""The drives' side of the protocol on a real SocketCAN bus, frame by frame:
heartbeat rate and contents, the reply to every message, malformed frames.
Frames are built and decoded with cantools from docs/triquint.dbc."""
import time

import can

from conftest import PROTOCOL_VERSION, QUEUE_CAPACITY

STATES = {0: "Idle", 1: "Loaded", 2: "Armed", 3: "Running", 4: "Stopping", 5: "Fault", 6: "Homing"}
# HeartbeatExt flags bits (protocol v2).
SYNCED, HOMED, CONFIGURED = 1, 2, 32


def collect(bus, seconds, pred=lambda m: True):
    out = []
    t0 = time.monotonic()
    while time.monotonic() - t0 < seconds:
        m = bus.recv(0.05)
        if m is not None and pred(m):
            out.append(m)
    return out


def send(bus, db, name, fd=False, **signals):
    msg = db.get_message_by_name(name)
    if name.startswith("Command_"):
        signals.setdefault("arg2", 0)
    data = msg.encode(signals)
    bus.send(can.Message(arbitration_id=msg.frame_id, data=data, is_extended_id=False,
                         is_fd=fd, bitrate_switch=fd))


def decode(db, m):
    return db.decode_message(m.arbitration_id, bytes(m.data), decode_choices=False)


def wait_for(bus, db, name, seconds=3.0, pred=lambda d: True):
    frame_id = db.get_message_by_name(name).frame_id
    t0 = time.monotonic()
    while time.monotonic() - t0 < seconds:
        m = bus.recv(0.05)
        if m is not None and m.arbitration_id == frame_id:
            d = decode(db, m)
            if pred(d):
                return d
    raise AssertionError(f"no {name} within {seconds} s")


def test_heartbeat_rate_and_contents(make_sim, bus, db):
    sim = make_sim("heartbeat")
    sim.wait_heartbeats(bus)
    window = 3.0
    frames = collect(bus, window, lambda m: 0x701 <= m.arbitration_id <= 0x703 or 0x741 <= m.arbitration_id <= 0x743)
    for node in (1, 2, 3):
        hb = [m for m in frames if m.arbitration_id == 0x700 + node]
        ext = [m for m in frames if m.arbitration_id == 0x740 + node]
        # 100 ms period (10 Hz); the emulated guest jitters, so ±25 %.
        assert 0.75 * window * 10 <= len(hb) <= 1.25 * window * 10 + 1, (node, len(hb))
        assert abs(len(ext) - len(hb)) <= 1
        gaps = [b.timestamp - a.timestamp for a, b in zip(hb, hb[1:])]
        mean = sum(gaps) / len(gaps)
        assert 0.08 <= mean <= 0.125, (node, mean)
        for m in hb:
            d = decode(db, m)
            assert m.dlc == 8
            assert d["protocol_version"] == PROTOCOL_VERSION
            assert STATES[d["state"]] == "Idle" and d["fault"] == 0
            assert d["config_crc"] == 0, "unconfigured at power-on"
            assert d["queue_depth"] == 0
        for m in ext:
            d = decode(db, m)
            # Not synced, not configured; homed (the simulator starts homed).
            assert d["next_seq"] == 0 and d["flags"] & SYNCED == 0
            assert d["flags"] & CONFIGURED == 0 and d["flags"] & HOMED
    sim.stop()


def test_each_message_is_answered(make_sim, bus, db):
    sim = make_sim("replies")
    sim.wait_heartbeats(bus)
    # Command to one node: CommandAck from that node only, token echoed.
    send(bus, db, "Command_2", command=9, token=77, arg=0)  # Reset
    d = wait_for(bus, db, "CommandAck_2", pred=lambda d: d["token"] == 77)
    assert d["command"] == 9 and d["result"] == 0 and STATES[d["state"]] == "Idle"
    # Broadcast command: every node answers.
    send(bus, db, "Command_All", command=9, token=78, arg=0)
    for n in (1, 2, 3):
        wait_for(bus, db, f"CommandAck_{n}", pred=lambda d: d["token"] == 78)
    # Unknown command code: BadCommand (14).
    send(bus, db, "Command_1", command=200, token=79, arg=0)
    d = wait_for(bus, db, "CommandAck_1", pred=lambda d: d["token"] == 79)
    assert d["result"] == 14
    # ConfigWrite of one parameter, then ConfigCommit with a CRC that cannot
    # match an incomplete set: ConfigMismatch (9), still unconfigured.
    send(bus, db, "ConfigWrite_3", index=0, axis=2.0)
    send(bus, db, "Command_3", command=8, token=80, arg=0x12345678)
    d = wait_for(bus, db, "CommandAck_3", pred=lambda d: d["token"] == 80)
    assert d["command"] == 8 and d["result"] == 9
    # ReadConfig: a ConfigValue for every parameter; the written one reads back.
    send(bus, db, "Command_3", command=10, token=81, arg=0)
    values = {}
    t0 = time.monotonic()
    while time.monotonic() - t0 < 3.0 and len(values) < 37:
        m = bus.recv(0.05)
        if m is not None and m.arbitration_id == 0x1C3:
            values[m.data[0]] = decode(db, m)
    assert len(values) == 37
    assert values[0]["axis"] == 2.0
    # TimeSync: after a few syncs every node reports a valid time base.
    t0 = time.monotonic()
    seq = 0
    while time.monotonic() - t0 < 0.6:
        seq = (seq + 1) % 256
        send(bus, db, "TimeSync", seq=seq, prev_tx_us=1_000_000 + int((time.monotonic() - t0) * 1e6) - 20_000)
        time.sleep(0.02)
    for n in (1, 2, 3):
        wait_for(bus, db, f"HeartbeatExt_{n}", pred=lambda d: d["flags"] & SYNCED)
    # Segment parts to unconfigured drives: SegmentAck WrongState (6) from each.
    golden = read_golden_segment()
    for data in golden:
        bus.send(can.Message(arbitration_id=0x100, data=data, is_extended_id=False))
    for n in (1, 2, 3):
        d = wait_for(bus, db, f"SegmentAck_{n}")
        assert d["result"] == 6 and d["capacity"] == QUEUE_CAPACITY
    # Emergency from the host: every node faults (HostEmergency, 5) and says so.
    send(bus, db, "Emergency_Host", code=5, state=0, ramp_100us=0, plan_time_us=0)
    for n in (1, 2, 3):
        d = wait_for(bus, db, f"Emergency_{n}")
        assert d["code"] == 5 and STATES[d["state"]] == "Fault"
    d = wait_for(bus, db, "Heartbeat_1")
    assert STATES[d["state"]] == "Fault" and d["fault"] == 5
    # ClearFault: back to Idle.
    send(bus, db, "Command_All", command=5, token=82, arg=0)
    for n in (1, 2, 3):
        d = wait_for(bus, db, f"CommandAck_{n}", pred=lambda d: d["token"] == 82)
        assert d["result"] == 0 and STATES[d["state"]] == "Idle"
    sim.stop()


def read_golden_segment():
    """The classic part frames of the golden segment (testdata/protocol/golden.txt)."""
    import os
    from conftest import ROOT
    parts = []
    with open(os.path.join(ROOT, "testdata", "protocol", "golden.txt")) as f:
        for line in f:
            if line.startswith("SegmentPart part"):
                parts.append(bytes.fromhex(line.split("|")[3].strip()))
    assert len(parts) == 20
    return parts


def acks(bus, db, seconds=3.0):
    """The result of the next SegmentAck of nodes 1, 2, 3."""
    got = {}
    t0 = time.monotonic()
    while time.monotonic() - t0 < seconds and len(got) < 3:
        m = bus.recv(0.05)
        if m is not None and 0x181 <= m.arbitration_id <= 0x183:
            got.setdefault(m.arbitration_id - 0x180, decode(db, m)["result"])
    return [got.get(n) for n in (1, 2, 3)]


def test_malformed_frames_are_rejected(make_sim, bus, db):
    sim = make_sim("malformed")
    sim.wait_heartbeats(bus)
    golden = read_golden_segment()
    # Short frames (payload below the declared length) and unknown identifiers: ignored.
    bus.send(can.Message(arbitration_id=0x031, data=b"\x09\x01", is_extended_id=False))
    bus.send(can.Message(arbitration_id=0x7FF, data=b"\x00" * 8, is_extended_id=False))
    bus.send(can.Message(arbitration_id=0x1234567, data=b"\x09\x01\x00\x00\x00\x00", is_extended_id=True))
    quiet = collect(bus, 0.5, lambda m: 0x1A1 <= m.arbitration_id <= 0x1A3)
    assert quiet == [], "no CommandAck for a malformed command"
    # A part out of order (part 1 without part 0): OutOfOrder (3).
    bus.send(can.Message(arbitration_id=0x100, data=golden[1], is_extended_id=False))
    assert acks(bus, db) == [3, 3, 3]
    # A corrupted word: the CRC over the body fails, BadCrc (1).
    bad = bytearray(golden[5])
    bad[4] ^= 0x01
    for i, data in enumerate(golden):
        bus.send(can.Message(arbitration_id=0x100, data=bytes(bad) if i == 5 else data, is_extended_id=False))
    assert acks(bus, db) == [1, 1, 1]
    # A new part 0 before the segment completed: Incomplete (7).
    for data in golden[:3] + golden[:1]:
        bus.send(can.Message(arbitration_id=0x100, data=data, is_extended_id=False))
    assert acks(bus, db) == [7, 7, 7]
    # The rejections are counted in HeartbeatExt, with the last reason.
    d = wait_for(bus, db, "HeartbeatExt_3", pred=lambda d: d["rejects"] >= 3)
    assert d["last_reject"] in (7, 1)
    # And the drives are unharmed: still Idle, no fault.
    d = wait_for(bus, db, "Heartbeat_2")
    assert STATES[d["state"]] == "Idle" and d["fault"] == 0
    sim.stop()
