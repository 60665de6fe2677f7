"""The static explorer as a class meets it, in headless Chromium (its software WebGPU): on a
phone (390 x 844, touch) and on a projector's 1280 x 800. On each: the first map (and its
coarse preview), a tap on the map's middle (the clicked start marked, its words, the swing
in sight), the map changed to the FTLE (the words follow the map shown), "Copy link".

Usage: class.py URL OUTDIR
Writes OUTDIR/phone.png and OUTDIR/projector.png; prints a report as JSON.
"""
import json
import sys

from selenium.webdriver.common.action_chains import ActionChains
from selenium.webdriver.support.ui import WebDriverWait

import chromium

url, out = sys.argv[1], sys.argv[2]
driver = chromium.start()
driver.set_script_timeout(300)
report = {}
STATE = """const p = window.chaoscope, rect = (id) => {
    const r = document.getElementById(id).getBoundingClientRect();
    return {left: r.left, top: r.top, right: r.right, bottom: r.bottom, width: r.width};
  };
  return {views: p.views, errors: p.errors, preview: p.previewSeconds || null,
    seconds: p.last && p.last.seconds, clicked: p.clickedText || null, copied: p.copied || null,
    href: location.href, status: document.getElementById('status').textContent,
    inner: [window.innerWidth, window.innerHeight], map: rect('map'), swing: rect('swing'),
    marker: document.getElementById('marker').hidden ? null : rect('marker'),
    command: document.getElementById('command').textContent};"""


def views_above(n):
    WebDriverWait(driver, 300, poll_frequency=0.1).until(
        lambda d: d.execute_script(f"return window.chaoscope.views > {n}"))


try:
    for name, (w, h, mobile) in {"phone": (390, 844, True),
                                 "projector": (1280, 800, False)}.items():
        driver.execute_cdp_cmd("Emulation.setDeviceMetricsOverride", {
            "width": w, "height": h, "deviceScaleFactor": 1, "mobile": mobile})
        driver.get(f"{url}?{name}#t_max=5")
        views_above(0)
        first = driver.execute_script(STATE)
        # A tap on the map's middle: the start there, marked, its swing shown.
        ActionChains(driver).move_to_element(driver.find_element("id", "map")).click().perform()
        WebDriverWait(driver, 120, poll_frequency=0.1).until(
            lambda d: d.execute_script("return Boolean(window.chaoscope.swung)"))
        tapped = driver.execute_script(STATE)
        # The map changed: the tapped start's words are the new map's.
        driver.execute_script("""const f = document.getElementById('controls');
          f.elements.kind.value = 'ftle'; f.dispatchEvent(new Event('change'));""")
        views_above(first["views"])
        changed = driver.execute_script(STATE)
        driver.find_element("id", "copy").click()
        WebDriverWait(driver, 10, poll_frequency=0.1).until(
            lambda d: d.execute_script("return Boolean(window.chaoscope.copied)"))
        copied = driver.execute_script(STATE)
        driver.save_screenshot(f"{out}/{name}.png")
        report[name] = {"first": first, "tapped": tapped, "changed": changed, "copied": copied}
finally:
    driver.quit()
print(json.dumps(report))
