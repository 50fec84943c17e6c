#!/usr/bin/env python3
"""Checks the invariants of a multi-rank render's --stats JSON: no ray traced
twice on a rank, rays forwarded (counted by senders) equal rays received
(counted by receivers), every shading re-trace found its hit, and, with proxy
forwarding, the proxies were asked about the camera rays: once per camera
path with a lens or in a view's first sample; with a pinhole, from a view's
second sample on, five rays a pixel once (each group's), then once per
camera path of a pixel whose five owners differ (the rank a pixel is dealt
to decides its owner for all; the queries weighing a replicated proxy's
owners are counted apart)."""
import json
import sys

s = json.load(open(sys.argv[1]))
r = s["render"]
fwd = r["total"]["exchange"]["rays_forwarded"]
assert r["revisits"] == 0, f"{r['revisits']} rays revisited a rank"
assert r["rays_received"] == fwd, f"forwarded {fwd} but received {r['rays_received']}"
assert r["total"]["traces"]["retrace_misses"] == 0, "re-trace missed the hit"
ex = r["total"]["exchange"]
kinds = ex["shadow_rays_forwarded"] + ex["forwarded_to_shade"]
assert kinds <= fwd, f"{kinds} shadow and to-shade forwards of {fwd}"
# Counted where rays arrive to be traversed: never more than were sent so.
fruitless = ex["visits_without_hit"]
assert fruitless <= fwd - ex["forwarded_to_shade"], \
    f"{fruitless} visits without a hit of {fwd - ex['forwarded_to_shade']} sent to be traversed"
if s["settings"]["forwarding"] == "broadcast" and fwd > 0:
    # Every copy's reply comes back traversed; a hit found elsewhere is sent to be shaded.
    assert ex["forwarded_to_shade"] > 0, "broadcast forwarded nothing to be shaded"
if s["settings"]["forwarding"] == "proxies" and s["settings"]["ranks"] > 1:
    camera = r["total"]["camera_paths"]
    queries = r["total"]["traces"]["proxy_queries"]
    replica = r["total"]["traces"]["replica_queries"]
    assert queries >= camera + replica, f"{queries} proxy queries for {camera} camera paths"
    primary = r["total"]["traces"]["primary_queries"]
    pixels = s["settings"]["image_width"] * s["settings"]["image_height"] \
        * s["settings"].get("data_groups", 1)
    assert primary == camera or pixels < primary <= camera + 5 * pixels, \
        f"{primary} primary-ownership queries for {camera} camera paths"
ex = r["total"]["exchange"]
if s["settings"].get("exchange") == "overlapped":
    # Rays travel in messages, never in collective rounds; every sample ends
    # with at least two termination sums (two with nothing changed).
    assert ex["rounds"] == 0, f"overlapped exchange counted {ex['rounds']} rounds"
    assert fwd == 0 or ex["messages"] > 0, "rays forwarded without a message"
    assert r["total"]["termination_waves"] >= 2, "a sample ended without two termination sums"
elif s["settings"]["ranks"] > 1:
    assert ex["messages"] == 0, "bulk exchange counted messages"
print(f"  forwarded {fwd}, rounds {ex['rounds']}, messages {ex['messages']}, "
      f"max estimated bytes per rank {s['memory']['max_estimated_bytes']:.0f}")
