#!/usr/bin/env python3
"""Checks a running `ferry view` through its API and, with --browser, through
its page in headless Chromium driven by chromedriver (the W3C WebDriver
protocol over plain HTTP: nothing beyond the standard library and Debian's
chromium and chromium-driver).

  viewer_check.py URL api                      the API: frames, PNGs, camera changes, bad requests
  viewer_check.py URL browser SCREENSHOT.png   load the page, check the image, drag to orbit
  viewer_check.py URL display                  AOVs shown instead of the colour (ferry view --aov albedo,normal)
  viewer_check.py URL memory FRAMES            let FRAMES frames pass; resident memory must stay flat
  viewer_check.py URL volume SCREENSHOT.png    a transfer-function volume restyled from the page and the API
  viewer_check.py URL field FIELD              the page renders another array of the VTK data (FIELD)
  viewer_check.py URL quit

Exits non-zero with a message on the first failed check. Every wait is bounded.
"""
import base64
import json
import os
import shutil
import socket
import struct
import subprocess
import sys
import tempfile
import time
import urllib.error
import urllib.parse
import urllib.request


def fail(message):
    print(f"FAIL: {message}", file=sys.stderr)
    sys.exit(1)


def request(url, method="GET", body=None, timeout=10):
    data = None if body is None else (body if isinstance(body, bytes) else body.encode())
    req = urllib.request.Request(url, data=data, method=method)
    try:
        with urllib.request.urlopen(req, timeout=timeout) as r:
            return r.status, dict(r.headers), r.read()
    except urllib.error.HTTPError as e:
        return e.code, dict(e.headers), e.read()


def raw_post(base, path):
    """A POST with no body and no Content-Length (urllib always sends one)."""
    url = urllib.parse.urlparse(base)
    with socket.create_connection((url.hostname, url.port), timeout=10) as s:
        s.sendall(f"POST /{path} HTTP/1.1\r\nHost: {url.hostname}\r\nConnection: close\r\n\r\n".encode())
        answer = b""
        while chunk := s.recv(4096):
            answer += chunk
    head, _, body = answer.partition(b"\r\n\r\n")
    return int(head.split()[1]), body


def stats(base):
    status, _, body = request(base + "stats")
    if status != 200:
        fail(f"GET /stats: {status}")
    return json.loads(body)


def wait_for(what, predicate, seconds=30):
    end = time.time() + seconds
    while time.time() < end:
        value = predicate()
        if value:
            return value
        time.sleep(0.05)
    fail(f"timed out after {seconds} s waiting for {what}")


def png_size(data):
    if data[:8] != b"\x89PNG\r\n\x1a\n" or data[12:16] != b"IHDR":
        fail("not a PNG")
    return struct.unpack(">II", data[16:24])


def check_api(base):
    s = stats(base)
    width, height = s["requested"]["settings"]["width"], s["requested"]["settings"]["height"]
    first = wait_for("a first frame", lambda: stats(base)["frames"] >= 1 and stats(base))
    status, headers, png = request(base + "frame.png")
    if status != 200 or png_size(png) != (width, height):
        fail(f"GET /frame.png: {status}, size {png_size(png) if status == 200 else '-'}, expected {width}x{height}")
    frame_id = int(headers["X-Ferry-Frame"])
    status, headers, _ = request(base + f"frame.png?after={frame_id}")
    if status != 200 or int(headers["X-Ferry-Frame"]) <= frame_id:
        fail("GET /frame.png?after=ID did not wait for a newer frame")
    grown = wait_for("frames to grow", lambda: stats(base)["frames"] > first["frames"] + 2 and stats(base))
    print(f"  frames grow: {first['frames']} -> {grown['frames']}, frame.png {width}x{height}")

    # A camera change restarts the accumulation and changes the image.
    camera = grown["camera"]
    moved = dict(camera, **{"from": [c + d for c, d in zip(camera["from"], (40.0, 25.0, 60.0))]})
    status, _, body = request(base + "camera", "POST", json.dumps(moved))
    if status != 200:
        fail(f"POST /camera: {status} {body!r}")
    after = wait_for("the new camera's first frames",
                     lambda: (lambda s: s["camera"]["from"] == moved["from"] and s)(stats(base)))
    if after["frames"] >= grown["frames"] + 5:
        fail(f"frames did not restart after a camera change ({grown['frames']} -> {after['frames']})")
    _, _, png2 = request(base + "frame.png")
    if png2 == png:
        fail("the image did not change with the camera")
    print(f"  camera change: frames restart ({grown['frames']} -> {after['frames']}), image changes")

    # A focus pick: the ranks find the surface under the point; the focal
    # distance they found becomes the camera's, and the frames restart.
    before = stats(base)
    status, _, body = request(base + "focus", "POST", json.dumps({"x": 0.5, "y": 0.5}))
    if status != 200:
        fail(f"POST /focus: {status} {body!r}")
    focused = wait_for("the picked focal distance",
                       lambda: (lambda s: s["requested"]["camera"]["focal_distance"]
                                != before["requested"]["camera"]["focal_distance"] and s)(stats(base)))
    distance = focused["requested"]["camera"]["focal_distance"]
    if not 100 < distance < 3000 or focused["camera"]["focal_distance"] != distance:
        fail(f"focus pick: focal distance {distance}, shown {focused['camera']['focal_distance']}")
    print(f"  focus pick: focal distance {before['requested']['camera']['focal_distance']:g} -> {distance:g}")

    # Settings: a new size gives PNGs of that size.
    status, _, body = request(base + "settings", "POST", json.dumps({"width": 48, "height": 32, "spp": 2}))
    if status != 200:
        fail(f"POST /settings: {status} {body!r}")
    wait_for("a 48x32 frame", lambda: png_size(request(base + "frame.png")[2]) == (48, 32))
    request(base + "settings", "POST", json.dumps({"width": width, "height": height, "spp": 1}))
    wait_for(f"a {width}x{height} frame again",
             lambda: png_size(request(base + "frame.png")[2]) == (width, height))
    print(f"  settings: 48x32 at 2 spp served, then {width}x{height} at 1 spp again")

    # Bad requests: 4xx with a reason, and the server stays up.
    corpus = [
        ("POST", "camera", "not json"), ("POST", "camera", "{}"), ("POST", "camera", "[1,2,3]"),
        ("POST", "camera", '{"from":[0,0,NaN],"at":[0,0,0]}'),
        ("POST", "camera", '{"from":[0,0,1e999],"at":[0,0,0]}'),
        ("POST", "camera", '{"from":[1,2,3],"at":[1,2,3]}'),
        ("POST", "camera", '{"from":[0,0,1],"at":[0,0,0],"roll":3}'),
        ("POST", "focus", '{"x":0.5}'), ("POST", "focus", '{"x":2,"y":0.5}'),
        ("POST", "settings", '{"width":1000000,"height":1000000}'),
        ("POST", "settings", '{"spp":-1}'), ("POST", "settings", '{"view":"nowhere"}'),
        ("POST", "settings", '{"exposure":"x"}'), ("POST", "settings", "\u0000\u0001"),
        ("POST", "settings", '{"color_map":"viridis"}'),  # no transfer-function volume here
        ("POST", "settings", "x" * 100000),  # over the body limit
        ("GET", "camera", None), ("GET", "nowhere", None), ("DELETE", "stats", None),
        ("GET", "frame.png?after=banana", None),
    ]
    # What some of them must say.
    reasons = {("POST", "camera", "{}"): b"are required",
               ("POST", "focus", '{"x":2,"y":0.5}'): b"in [0, 1]",
               ("POST", "settings", "x" * 100000): b"over the 65536-byte limit",
               ("GET", "nowhere", None): b"no such endpoint",
               ("DELETE", "stats", None): b"no such endpoint"}
    for method, path, body in corpus:
        status, _, answer = request(base + path, method, body)
        if not 400 <= status < 500:
            fail(f"{method} /{path} {body!r:.40}: status {status}, expected 4xx")
        if not answer:
            fail(f"{method} /{path}: a {status} without a reason")
        if reasons.get((method, path, body), b"") not in answer:
            fail(f"{method} /{path}: {answer!r:.120} does not say {reasons[(method, path, body)]!r}")
        if stats(base)["frames"] < 1 and request(base + "stats")[0] != 200:
            fail("the server went down")
    status, _, _ = request(base + "stats")
    if status != 200:
        fail("the server did not survive the bad requests")
    print(f"  {len(corpus)} bad requests: each a 4xx with a reason, the server still up")


class WebDriver:
    """The few W3C WebDriver commands this check needs."""

    def __init__(self):
        self.port = free_port()
        self.process = subprocess.Popen(["chromedriver", f"--port={self.port}"],
                                        stdout=subprocess.DEVNULL, stderr=subprocess.DEVNULL)
        self.base = f"http://127.0.0.1:{self.port}"
        self.profile = tempfile.mkdtemp(prefix="ferry-chromium-")
        wait_for("chromedriver", lambda: self._ready(), 20)
        args = ["--headless=new", "--no-sandbox", "--disable-gpu", "--disable-dev-shm-usage",
                "--window-size=1100,760", f"--user-data-dir={self.profile}"]
        caps = {"capabilities": {"alwaysMatch": {"browserName": "chrome",
                                                 "goog:chromeOptions": {"binary": "/usr/bin/chromium",
                                                                        "args": args}}}}
        self.session = self.call("POST", "/session", caps)["sessionId"]

    def _ready(self):
        try:
            return request(self.base + "/status", timeout=2)[0] == 200
        except OSError:
            return False

    def call(self, method, path, body=None):
        if path != "/session" and not path.startswith("/session/"):
            path = f"/session/{self.session}{path}"
        status, _, data = request(self.base + path, method, None if body is None else json.dumps(body), 60)
        value = json.loads(data)["value"] if data else None
        if status != 200:
            fail(f"WebDriver {method} {path}: {status} {value}")
        return value

    def script(self, source, *args):
        return self.call("POST", "/execute/sync", {"script": source, "args": list(args)})

    def close(self):
        try:
            self.call("DELETE", "")
        finally:
            self.process.terminate()
            self.process.wait(10)
            shutil.rmtree(self.profile, ignore_errors=True)


def free_port():
    with socket.socket() as s:
        s.bind(("127.0.0.1", 0))
        return s.getsockname()[1]


# Mean brightness and spread of the page's image (0..255), read through a canvas.
IMAGE_STATS = """
const img = document.getElementById('frame');
if (!img.complete || img.naturalWidth === 0) return null;
const c = document.createElement('canvas');
c.width = img.naturalWidth; c.height = img.naturalHeight;
const g = c.getContext('2d'); g.drawImage(img, 0, 0);
const d = g.getImageData(0, 0, c.width, c.height).data;
let sum = 0, sum2 = 0, n = 0;
for (let i = 0; i < d.length; i += 4) { const v = (d[i] + d[i + 1] + d[i + 2]) / 3; sum += v; sum2 += v * v; n++; }
const mean = sum / n;
return {mean: mean, spread: Math.sqrt(Math.max(0, sum2 / n - mean * mean)), width: c.width};
"""


def check_browser(base, screenshot):
    driver = WebDriver()
    try:
        driver.call("POST", "/url", {"url": base})
        shown = wait_for("the page to show an image", lambda: driver.script(IMAGE_STATS), 30)
        if shown["mean"] < 2 or shown["spread"] < 2:
            fail(f"the page's image is blank: {shown}")
        wait_for("the page to know the camera", lambda: driver.script("return camera !== null"), 20)
        frames_before = wait_for("frames to accumulate", lambda: (lambda s: s["frames"] >= 4 and s)(stats(base)))
        camera_before = frames_before["camera"]
        # Drag across the image: the page orbits the camera.
        rect = driver.script("const r = document.getElementById('frame').getBoundingClientRect();"
                             "return {x: r.left + r.width / 2, y: r.top + r.height / 2};")
        x, y = int(rect["x"]), int(rect["y"])
        moves = [{"type": "pointerMove", "duration": 0, "x": x, "y": y}, {"type": "pointerDown", "button": 0}]
        moves += [{"type": "pointerMove", "duration": 30, "x": x + 12 * i, "y": y + 3 * i} for i in range(1, 11)]
        moves += [{"type": "pointerUp", "button": 0}]
        driver.call("POST", "/actions", {"actions": [{"type": "pointer", "id": "mouse",
                                                      "parameters": {"pointerType": "mouse"},
                                                      "actions": moves}]})
        moved = wait_for("the camera to move after the drag",
                         lambda: (lambda s: s["camera"]["from"] != camera_before["from"] and s)(stats(base)), 20)
        if moved["frames"] >= frames_before["frames"] + 5:
            fail(f"frames did not restart after the drag ({frames_before['frames']} -> {moved['frames']})")
        # Double-click off the centre: the page asks for a focus pick there.
        focus_before = stats(base)["requested"]["camera"]["focal_distance"]
        driver.script("const r = document.getElementById('frame').getBoundingClientRect();"
                      "document.getElementById('view').dispatchEvent(new MouseEvent('dblclick', "
                      "{bubbles: true, clientX: r.left + r.width * 0.45, clientY: r.top + r.height * 0.55}));")
        focused = wait_for("the double-click's focal distance",
                           lambda: (lambda s: s["requested"]["camera"]["focal_distance"] != focus_before and s)(stats(base)), 20)
        wait_for("the page to show it", lambda: driver.script(
            "return Number(document.getElementById('focus').value) === Number(camera.focal_distance.toPrecision(6))"
            " && camera.focal_distance === %r" % focused["requested"]["camera"]["focal_distance"]), 20)
        # The page shows the new camera's image.
        wait_for("the page to show the orbited image",
                 lambda: (lambda s: s and abs(s["mean"] - shown["mean"]) > 0.01 and s)(driver.script(IMAGE_STATS)), 20)
        time.sleep(1.0)  # let a few frames accumulate for the picture
        png = base64.b64decode(driver.call("GET", "/screenshot"))
        png_size(png)
        os.makedirs(os.path.dirname(os.path.abspath(screenshot)), exist_ok=True)
        with open(screenshot, "wb") as f:
            f.write(png)
        print(f"  browser: image shown (mean {shown['mean']:.0f}, spread {shown['spread']:.0f}), "
              f"drag orbits the camera, frames restart ({frames_before['frames']} -> {moved['frames']}), "
              f"double-click focuses ({focus_before:g} -> {focused['requested']['camera']['focal_distance']:g}); "
              f"screenshot {screenshot}")
    finally:
        driver.close()


def check_volume(base, screenshot):
    s = wait_for("a first frame", lambda: (lambda s: s["frames"] >= 2 and s)(stats(base)))
    if "color_maps" not in s or "viridis" not in s["color_maps"]:
        fail(f"/stats offers no colour maps for a volume: {sorted(s)}")
    _, _, before = request(base + "frame.png")
    driver = WebDriver()
    try:
        driver.call("POST", "/url", {"url": base})
        wait_for("the page's volume controls",
                 lambda: driver.script("return !document.getElementById('volume').hidden"), 20)
        # Pick a colour map on the page, as a user would.
        driver.script("const m = document.getElementById('colormap'); m.value = 'inferno';"
                      "m.dispatchEvent(new Event('change'));")
        picked = wait_for("the colour map to be taken",
                          lambda: (lambda s: s["settings"]["color_map"] == "inferno" and s)(stats(base)), 20)
        if picked["frames"] >= s["frames"] + 20:
            fail("frames did not restart after the colour map changed")
        wait_for("the restyled image", lambda: request(base + "frame.png")[2] != before, 20)
        # And the opacity slider.
        driver.script("const o = document.getElementById('opacity'); o.value = '2';"
                      "o.dispatchEvent(new Event('change'));")
        wait_for("the opacity scale to be taken",
                 lambda: stats(base)["settings"]["volume_opacity"] == 4, 20)
        time.sleep(1.0)
        png = base64.b64decode(driver.call("GET", "/screenshot"))
        os.makedirs(os.path.dirname(os.path.abspath(screenshot)), exist_ok=True)
        with open(screenshot, "wb") as f:
            f.write(png)
    finally:
        driver.close()
    status, _, body = request(base + "settings", "POST", json.dumps({"color_map": "jet"}))
    if status != 400 or b"no colour map named" not in body:
        fail(f"an unknown colour map: {status} {body!r}")
    print(f"  volume: colour maps {s['color_maps']}; the page's map and opacity restyle it "
          f"(frames restart, image changes); an unknown map is a 400; screenshot {screenshot}")


def check_field(base, field):
    """A .vti with several arrays: /stats lists them with their ranges, the
    page's field choice reads the scene again rendering FIELD (the image
    changes, frames go on), an unknown array is a 400."""
    s = wait_for("a first frame", lambda: (lambda s: s["frames"] >= 2 and s)(stats(base)))
    fields = {f["name"]: f for f in s.get("fields", [])}
    if field not in fields or s.get("field") == field or len(fields) < 2:
        fail(f"/stats fields {s.get('fields')!r}, shown {s.get('field')!r}: expected {field} among "
             "several, not shown yet")
    for f in fields.values():
        if not (f["range"][0] <= f["range"][1]):
            fail(f"field {f['name']}: range {f['range']}")
    _, _, before = request(base + "frame.png")
    driver = WebDriver()
    try:
        driver.call("POST", "/url", {"url": base})
        wait_for("the page's field choice",
                 lambda: driver.script("return !document.getElementById('fieldBox').hidden"), 20)
        options = driver.script(
            "return [...document.getElementById('field').options].map((o) => o.text)")
        if not any(o.startswith(field + " (points) [") for o in options):
            fail(f"the page's fields {options!r} do not show {field} with its range")
        driver.script("const f = document.getElementById('field'); f.value = arguments[0];"
                      "f.dispatchEvent(new Event('change'));", field)
        wait_for(f"the scene read again for {field}",
                 lambda: (lambda s: s.get("field") == field and "loading_field" not in s
                          and s["frames"] >= 2)(stats(base)), 60)
        wait_for("the other field's image", lambda: request(base + "frame.png")[2] != before, 20)
        wait_for(f"the page to show {field} as the field",
                 lambda: driver.script("return document.getElementById('field').value") == field, 20)
    finally:
        driver.close()
    status, _, body = request(base + "settings", "POST", json.dumps({"field": "no-such-array"}))
    if status != 400 or b"no array named" not in body:
        fail(f"an unknown field: {status} {body!r}")
    print(f"  field: {sorted(fields)} listed with ranges; the page chose {field}, the ranks read "
          "the data again and the image changed; an unknown array is a 400")


def check_display(base):
    """`ferry view --aov albedo,normal`: "display" shows an AOV without
    restarting the frames, an AOV not held is a 400, "color" comes back."""
    s = wait_for("a first frame", lambda: (lambda s: s["frames"] >= 2 and s)(stats(base)))
    if s.get("displays") != ["color", "albedo", "normal"]:
        fail(f"/stats displays: {s.get('displays')!r}, expected color, albedo, normal")
    if s["requested"]["settings"]["display"] != "color":
        fail(f"the first display is {s['requested']['settings']['display']!r}, not color")
    _, _, color_png = request(base + "frame.png")
    for name in ("normal", "albedo"):
        status, _, body = request(base + "settings", "POST", json.dumps({"display": name}))
        if status != 200:
            fail(f"POST /settings display {name}: {status} {body!r}")
        before = stats(base)["frames"]
        shown = wait_for(f"a frame showing {name}",
                         lambda: (lambda s: s["settings"]["display"] == name and s)(stats(base)))
        if shown["frames"] < before:
            fail(f"showing {name} restarted the frames ({before} -> {shown['frames']})")
        _, _, png = request(base + "frame.png")
        if png == color_png:
            fail(f"the {name} picture is the colour picture")
    status, _, body = request(base + "settings", "POST", json.dumps({"display": "depth"}))
    if status != 400 or b"the frames hold color, albedo,normal" not in body:
        fail(f"an AOV not held: {status} {body!r}")
    status, _, _ = request(base + "settings", "POST", json.dumps({"display": "color"}))
    wait_for("the colour again", lambda: stats(base)["settings"]["display"] == "color")
    print("  display: albedo and normal shown without restarting the frames; an AOV not held is a 400")


def check_memory(base, frames):
    def resident():
        s = stats(base)
        return s["frames"], s["frame_id"], [m["resident_bytes"] for m in s["memory_per_rank"]]
    wait_for("100 frames", lambda: stats(base)["frame_id"] >= 100, 120)
    _, id0, early = resident()
    wait_for(f"{frames} frames", lambda: stats(base)["frame_id"] >= frames, 600)
    _, id1, late = resident()
    growth = [(b - a) / 2**20 for a, b in zip(early, late)]
    print(f"  frames {id0} -> {id1}: resident MiB per rank {[round(x / 2**20, 1) for x in late]}, "
          f"growth {[round(g, 2) for g in growth]}")
    if os.environ.get("ASAN_OPTIONS"):
        # Under AddressSanitizer (scripts/sanitize.sh) the resident set grows
        # with its quarantine of freed memory, not the program's own.
        print("  (ASan: growth not checked)")
    elif max(growth) > 4:
        fail(f"resident memory grew by {max(growth):.1f} MiB over {id1 - id0} frames")


def main():
    if len(sys.argv) < 3:
        fail(__doc__)
    base, what = sys.argv[1].rstrip("/") + "/", sys.argv[2]
    if what == "api":
        check_api(base)
    elif what == "display":
        check_display(base)
    elif what == "browser":
        check_browser(base, sys.argv[3])
    elif what == "volume":
        check_volume(base, sys.argv[3])
    elif what == "field":
        check_field(base, sys.argv[3])
    elif what == "memory":
        check_memory(base, int(sys.argv[3]))
    elif what == "quit":
        # As `curl -X POST URL/quit` sends it: no body and no Content-Length.
        status, answer = raw_post(base, "quit")
        if status != 200:
            fail(f"POST /quit without a body: {status} {answer!r}")
    else:
        fail(f"unknown check {what}")


if __name__ == "__main__":
    main()
