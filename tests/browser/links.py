"""Opens the static explorer (`chaoscope web`) in headless Chromium (its software WebGPU) once
for each of a list of addresses' hashes, as a link sent to a class would open it, and reports
what the page did with each: what it refused, its status line, whether it computed, and any
error its script did not catch. Each load is a fresh page (a query string of its own); a view
that computes is left after its first words (the next load ends it).

Usage: links.py URL HASHES_JSON [FILE_URL]
  HASHES_JSON: a list of hashes (without the "#"), their values percent-encoded.
  FILE_URL: the same page opened from disk (file://...): its status line is reported too.
Prints {"cases": [{"hash", "refused", "status", "views", "ready", "error", "errors",
"seconds"}], "from_disk": status} as JSON.
"""
import json
import sys
import time

from selenium.webdriver.support.ui import WebDriverWait

import chromium

url, hashes = sys.argv[1], json.loads(sys.argv[2])
from_disk = sys.argv[3] if len(sys.argv) > 3 else None
driver = chromium.start()
# A small window: a view the page accepts starts on a small map.
driver.execute_cdp_cmd("Emulation.setDeviceMetricsOverride", {
    "width": 640, "height": 400, "deviceScaleFactor": 1, "mobile": False})
cases = []
# The page has settled on a link once it refused it, computes or computed it, said why it
# will not (a view too deep, axes that clash, a range left), or found no GPU.
SETTLED = """const p = window.chaoscope, s = document.getElementById('status').textContent;
  return Boolean(p && (p.error || p.views > 0 || (p.ready && !s.startsWith('starting'))));"""
try:
    for i, h in enumerate(hashes):
        started = time.time()
        driver.get(f"{url}?link={i}#{h}")
        try:
            WebDriverWait(driver, 60, poll_frequency=0.05).until(
                lambda d: d.execute_script(SETTLED))
        except Exception:  # noqa: BLE001 (a page that never settles is the finding)
            pass
        state = driver.execute_script("""const p = window.chaoscope || {};
          return {refused: p.refused || null, views: p.views, ready: p.ready,
            error: p.error || null, errors: p.errors || null,
            status: document.getElementById('status').textContent};""")
        state["hash"] = h
        state["seconds"] = time.time() - started
        cases.append(state)
        driver.get("about:blank")
    report = {"cases": cases}
    if from_disk:
        driver.get(from_disk)
        WebDriverWait(driver, 60, poll_frequency=0.05).until(lambda d: d.execute_script(
            "return Boolean(window.chaoscope && window.chaoscope.error)"))
        report["from_disk"] = driver.find_element("id", "status").text
finally:
    driver.quit()
print(json.dumps(report))
