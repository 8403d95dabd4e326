import can

def test_vcan_round_trip():
    with can.Bus(interface="socketcan", channel="vcan0", fd=True, receive_own_messages=True) as bus:
        bus.send(can.Message(arbitration_id=0x123, data=b"\x01\x02", is_extended_id=False))
        m = bus.recv(2.0)
        assert m is not None and m.arbitration_id == 0x123
