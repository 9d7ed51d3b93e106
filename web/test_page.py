#!/usr/bin/env python3
"""The page test: web/site (web/build.sh) served on localhost and loaded in headless Chromium
with WebGPU (SwiftShader), once per setting; each run must reach its end with no console
error, draw a non-empty scene and a force plot, and end with the numbers of the same scene
run natively on the CPU path (examples/page_scene.rs). Saves a screenshot of each run and a
JSON of the page's times per increment in the output directory.

    python3 web/test_page.py [--out target/web] [--screenshot docs/page.png]
"""
import argparse
import functools
import http.server
import json
import os
import subprocess
import sys
import tempfile
import threading

from PIL import Image
from selenium import webdriver
from selenium.webdriver.chrome.service import Service
from selenium.webdriver.support.ui import WebDriverWait

ROOT = os.path.dirname(os.path.dirname(os.path.abspath(__file__)))
SITE = os.path.join(ROOT, "web", "site")

# (query, native arguments): the page's default (finite sliding, friction below the slope's
# tangent: the beads slide off) and its other corner (small sliding, friction above it)
RUNS = [
    dict(beads=1024, friction=0.2, scale=1, sliding="finite", frames=120, per_frame=20),
    dict(beads=1024, friction=0.5, scale=2, sliding="small", frames=60, per_frame=20),
]
# Headless Chromium without a GPU presents a WebGPU canvas only through Vulkan's SwiftShader
# (without these its compositor cannot make the canvas's swap chain and destroys the device);
# a browser on a machine with a GPU needs none of them
FLAGS = ["--headless=new", "--no-sandbox", "--enable-unsafe-webgpu", "--enable-features=Vulkan",
         "--use-vulkan=swiftshader", "--use-angle=vulkan", "--enable-unsafe-swiftshader",
         "--no-first-run", "--disable-background-networking", "--disable-component-update",
         "--disable-sync", "--window-size=1240,900"]


def native(run):
    """The same scene on the CPU path, natively: its summary."""
    args = [str(run[k]) for k in ("beads", "friction", "scale", "sliding", "frames", "per_frame")]
    out = subprocess.run(
        ["cargo", "run", "--release", "--quiet", "--example", "page_scene", "--", *args, "cpu"],
        cwd=ROOT, check=True, capture_output=True, text=True).stdout
    return json.loads(out)["devices"][0]["summary"]


class Quiet(http.server.SimpleHTTPRequestHandler):
    def log_message(self, *args):
        pass


def serve():
    handler = functools.partial(Quiet, directory=SITE)
    server = http.server.ThreadingHTTPServer(("127.0.0.1", 0), handler)
    threading.Thread(target=server.serve_forever, daemon=True).start()
    return server


def browser():
    o = webdriver.ChromeOptions()
    o.binary_location = "/usr/bin/chromium"
    for flag in FLAGS + [f"--user-data-dir={tempfile.mkdtemp()}"]:
        o.add_argument(flag)
    for flag in os.environ.get("ABUT_PAGE_FLAGS", "").split():
        o.add_argument(flag)
    o.set_capability("goog:loggingPrefs", {"browser": "ALL"})
    if os.environ.get("ABUT_PAGE_LOG"):
        o.add_argument("--enable-logging=stderr")
        o.add_argument("--v=1")
        service = Service("/usr/bin/chromedriver", log_output=os.environ["ABUT_PAGE_LOG"])
    else:
        service = Service("/usr/bin/chromedriver")
    return webdriver.Chrome(options=o, service=service)


def canvas_pixels(shot, driver, canvas_id):
    """Distinct colours inside the canvas in the screenshot."""
    r = driver.execute_script(
        "const r = document.getElementById(arguments[0]).getBoundingClientRect();"
        "return [r.left, r.top, r.right, r.bottom, window.devicePixelRatio];", canvas_id)
    k = r[4]
    box = tuple(int(v * k) for v in r[:4])
    return len(set(shot.crop((box[0] + 2, box[1] + 2, box[2] - 2, box[3] - 2)).get_flattened_data()))


def main():
    ap = argparse.ArgumentParser()
    ap.add_argument("--out", default=os.path.join(ROOT, "target", "web"))
    ap.add_argument("--screenshot", help="also save the first run's screenshot here")
    a = ap.parse_args()
    os.makedirs(a.out, exist_ok=True)
    server = serve()
    failures = []
    report = []
    for i, run in enumerate(RUNS):
        # a browser per run: Chromium would not leave a page holding a WebGPU device
        driver = browser()
        try:
            query = "&".join(f"{k}={v}" for k, v in run.items())
            url = f"http://127.0.0.1:{server.server_port}/index.html?{query}"
            driver.get(url)
            WebDriverWait(driver, 600, poll_frequency=0.5).until(
                lambda d: d.execute_script("return document.body.dataset.state") in ("done", "failed"))
            state = driver.execute_script("return document.body.dataset.state")
            log = driver.get_log("browser")
            errors = [e["message"] for e in log if e["level"] == "SEVERE"]
            path = os.path.join(a.out, f"page_{i}.png")
            driver.save_screenshot(path)
            if state != "done":
                failures.append(f"{query}: the page stopped: "
                                + driver.execute_script("return document.getElementById('error').textContent")
                                + "\n" + "\n".join(e["message"] for e in log))
                break
            if errors:
                failures.append(f"{query}: console errors: {errors}")
            shot = Image.open(path).convert("RGB")
            scene_colours = canvas_pixels(shot, driver, "scene")
            plot_colours = canvas_pixels(shot, driver, "plot")
            if scene_colours < 20:
                failures.append(f"{query}: the scene canvas shows {scene_colours} colours")
            if plot_colours < 5:
                failures.append(f"{query}: the force plot shows {plot_colours} colours")
            page = driver.execute_script("return window.abutResult")
            mine = [page["on_plate"], *page["mean"], page["normal_force"]]
            theirs = native(run)
            weight = 1024 * 0.01 * 9.81
            # the same f32 arithmetic in the same order: the CPU path's numbers to round-off of
            # a sum (Chromium 156's SwiftShader gives them bit for bit)
            tol = [0, 1e-5, 1e-5, 1e-5, 1e-5 * weight]
            diff = [abs(x - y) for x, y in zip(mine, theirs)]
            if any(d > t for d, t in zip(diff, tol)):
                failures.append(f"{query}: page {mine} against native {theirs}")
            times = page["frame_ms_per_increment"]
            steady = sorted(times[1:])[len(times[1:]) // 2]
            report.append(dict(run=run, page=mine, native=theirs, largest_difference=max(diff),
                               first_frame_ms_per_increment=times[0],
                               median_ms_per_increment=steady,
                               scene_colours=scene_colours, plot_colours=plot_colours,
                               adapter="Chromium " + driver.capabilities["browserVersion"]
                               + " WebGPU (SwiftShader)"))
            print(f"page {query}: {state}, {scene_colours} colours in the scene, page {mine}, "
                  f"native {theirs}, {steady:.3f} ms per increment (median frame)")
            if i == 0 and a.screenshot:
                shot.save(a.screenshot)
        finally:
            driver.quit()
    server.shutdown()
    with open(os.path.join(a.out, "page.json"), "w") as f:
        json.dump(report, f, indent=1)
    if failures:
        print("\n".join(failures), file=sys.stderr)
        sys.exit(1)


if __name__ == "__main__":
    main()
