"""Prints the figures of the HIL run (scripts/hil.sh): per paper case and bus,
upload time, frames, bus load and tracking error over vcan (triquint upload
against triquint-sim in the VM) next to the in-process simulation; then the
same for issue 35's streaming fixtures (test_streaming.py)."""
import json
import os
import sys

out = sys.argv[1]


def load(name):
    try:
        with open(os.path.join(out, name)) as f:
            return json.load(f)
    except (OSError, ValueError):
        return None


rows = []
for case in (1, 2):
    for bus in ("classic", "fd"):
        up = load(f"upload-case{case}-{bus}.json")
        sim = load(f"sim-case{case}-{bus}.json")
        inproc = load(f"inproc-case{case}{'-fd' if bus == 'fd' else ''}.json")
        rows.append((case, bus, up, sim, inproc))

um = lambda v: f"{max(v) * 1e6:.2f}"
print(f"{'case':5} {'bus':8} {'upload s':>9} {'total s':>8} {'frames':>7} {'seg fr':>7} "
      f"{'load vcan':>10} {'load inproc':>11} {'RMS µm vcan':>12} {'RMS µm inproc':>14} "
      f"{'max µm vcan':>12} {'max µm inproc':>14} {'missed':>7}")
for case, bus, up, sim, inproc in rows:
    if not (up and sim):
        print(f"{case:<5} {bus:8} (no result)")
        continue
    ip = inproc or {}
    print(f"{case:<5} {bus:8} {up['upload_s']:9.3f} {up['total_s']:8.3f} {sim['frames']:7d} "
          f"{sim['segment_frames']:7d} {100 * sim['bus_load']:9.2f}% "
          f"{100 * ip.get('bus_load', float('nan')):10.2f}% {um(sim['rms_error_m']):>12} "
          f"{um(ip['rms_error_m']) if ip else '-':>14} {um(sim['max_error_m']):>12} "
          f"{um(ip['max_error_m']) if ip else '-':>14} "
          f"{sim['missed_deadlines']:>4}/{sim['ticks']}")

print()
print(f"{'streaming fixture':24} {'bus':8} {'segments':>8} {'plan s':>7} {'upload s':>9} "
      f"{'seg fr':>7} {'load vcan':>10} {'load inproc':>11} {'max µm vcan':>12} {'missed':>7}")
for name in ("stream-15-segments", "stream-2ms-every-tenth", "stream-2000-segments"):
    for bus in ("classic", "fd"):
        s = load(f"streaming-{name}-{bus}.json")
        ip = load(f"inproc-{name}{'-fd' if bus == 'fd' else ''}.json") or {}
        if not s:
            print(f"{name:24} {bus:8} (no result)")
            continue
        print(f"{name:24} {bus:8} {s['segments']:8d} {s['plan_s']:7.3f} {s['upload_s']:9.3f} "
              f"{s['segment_frames']:7d} {100 * s['bus_load']:9.2f}% "
              f"{100 * ip.get('bus_load', float('nan')):10.2f}% {um(s['max_error_m']):>12} "
              f"{s['missed_deadlines']:>4}/{s['ticks']}")
