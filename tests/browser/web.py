"""Drives the static explorer (`chaoscope web`) in a real headless Chromium with its software
WebGPU adapter (SwiftShader), through WebDriver (selenium with Debian's chromedriver): loads
the page, waits for its first map and saves a screenshot, then asks the page for each view's
map (flip times or a divergence map, written as little-endian f32s), its command line, and whether f32 resolves it;
with OUTDIR, saves the first map as "Save PNG" downloads it, as OUTDIR/shown.png.

Usage: web.py [--no-webgpu] URL SCREENSHOT [OUTDIR VIEWS_JSON]
  --no-webgpu: Chromium without WebGPU; reports where the page went (served by `chaoscope
  serve`, it goes to the server's explorer) once a map is there.
  URL: the page, with a view in its hash (default #t_max=10: the whole plane over 10 s).
  VIEWS_JSON: a list of {"name", "width", "height", "view": {kind, cx, cy, w, t_max, dt,
  pendulum, x, y}, "times": false to skip the map, "swing": {theta1, ...} to add the run a
  click on that start swings, "verdict": true to add the verdict's mask as OUTDIR/NAME.mask,
  a byte a pixel}; writes OUTDIR/NAME.f32 for each map; prints a report as JSON
  (timings in seconds).
"""
import base64
import json
import os
import signal
import sys
import time

from selenium.webdriver.support.ui import WebDriverWait

import chromium

args = sys.argv[1:]
webgpu = args[0] != "--no-webgpu"
args = args if webgpu else args[1:]
url, screenshot = args[0], args[1]
out, views = (args[2], json.loads(args[3])) if len(args) > 3 else (None, [])
driver = chromium.start(webgpu)
driver.set_script_timeout(900)
report = {"views": {}}


def page_call(name, *args):
    """The page's test hook `name` called with args, awaited."""
    result = driver.execute_async_script(f"""
        const done = arguments[arguments.length - 1];
        Promise.resolve(window.chaoscope.{name}(...Array.from(arguments).slice(0, -1)))
          .then(done, (e) => done({{error: String(e && e.message || e)}}));""", *args)
    if isinstance(result, dict) and "error" in result:
        raise RuntimeError(f"{name}: {result['error']}")
    return result


def kill_gpu_process():
    """Kills this browser's GPU process (a descendant of our chromedriver, never another
    test's browser); returns how many processes it killed."""
    parent = {}
    for pid in filter(str.isdigit, os.listdir("/proc")):
        try:
            with open(f"/proc/{pid}/stat") as f:
                parent[int(pid)] = int(f.read().rsplit(")", 1)[1].split()[1])
        except (OSError, IndexError, ValueError):
            pass
    mine, killed = {driver.service.process.pid}, 0
    for _ in range(4):  # chromedriver -> chromium -> its children
        mine |= {pid for pid, up in parent.items() if up in mine}
    for pid in mine:
        try:
            with open(f"/proc/{pid}/cmdline", "rb") as f:
                if b"--type=gpu-process" in f.read():
                    os.kill(pid, signal.SIGKILL)
                    killed += 1
        except OSError:
            pass
    return killed


try:
    driver.execute_cdp_cmd("Emulation.setDeviceMetricsOverride", {
        "width": 1100, "height": 640, "deviceScaleFactor": 1, "mobile": False})
    driver.get(url if "#" in url else url + "#t_max=10")
    if not webgpu:
        # The server's explorer (its page object has firstView), or the page's own words.
        WebDriverWait(driver, 120, poll_frequency=0.1).until(lambda d: d.execute_script(
            "const p = window.chaoscope; return p && (p.firstView || (p.error && "
            "!document.getElementById('status').textContent.includes('computes the view')))"))
        time.sleep(1.0)  # Leaflet fades new tiles in
        report["location"] = driver.current_url
        report["status"] = driver.find_element("id", "status").text
        driver.save_screenshot(screenshot)
        views = []
    WebDriverWait(driver, 600, poll_frequency=0.1).until(lambda d: not webgpu or d.execute_script(
        "return window.chaoscope && (window.chaoscope.views > 0 || window.chaoscope.error)"))
    if webgpu:
        for key in ["error", "last", "adapter"]:
            report[key] = driver.execute_script(f"return window.chaoscope.{key}")
        report["status"] = driver.find_element("id", "status").text
        driver.save_screenshot(screenshot)
        if out and not report["error"]:
            # The map shown, as "Save PNG" downloads it.
            with open(f"{out}/shown.png", "wb") as f:
                f.write(base64.b64decode(page_call("png")))
    for v in views:
        name, w, h = v["name"], v["width"], v["height"]
        if v.get("lose_device"):
            views_before, lost_before = driver.execute_script(
                "return [window.chaoscope.views, window.chaoscope.lost]")
            report["gpu_processes_killed"] = kill_gpu_process()
            WebDriverWait(driver, 300, poll_frequency=0.1).until(lambda d: d.execute_script(
                f"const p = window.chaoscope; return p.lost > {lost_before} && "
                f"p.views > {views_before}"))
            report["lost"] = driver.execute_script("return window.chaoscope.lost")
            report["status_after_loss"] = driver.find_element("id", "status").text
        report["views"][name] = {"command": page_call("command", v["view"], w, h),
                                 "resolves": page_call("resolves", v["view"], w, h)}
        if "swing" in v:
            report["views"][name]["swing"] = page_call("swing", v["swing"], v["view"],
                                                       v.get("at"))
        if v.get("verdict"):
            started = time.time()
            data = page_call("verdict", v["view"], w, h)
            report["views"][name]["verdict_seconds"] = time.time() - started
            with open(f"{out}/{name}.mask", "wb") as f:
                f.write(base64.b64decode(data))
        if v.get("refused"):
            try:
                page_call("values", v["view"], w, h)
                report["views"][name]["refused"] = None
            except RuntimeError as e:
                report["views"][name]["refused"] = str(e)
            continue
        if v.get("times", True):
            started = time.time()
            data = page_call("values", v["view"], w, h)
            report["views"][name]["seconds"] = time.time() - started
            report["views"][name]["compute_seconds"] = driver.execute_script(
                "return window.chaoscope.computeSeconds")
            report["views"][name]["range"] = driver.execute_script(
                "return window.chaoscope.valuesRange")
            with open(f"{out}/{name}.f32", "wb") as f:
                f.write(base64.b64decode(data))
finally:
    driver.quit()
print(json.dumps(report))
