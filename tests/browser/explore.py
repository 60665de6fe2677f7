"""Drives the explorer in a real headless Chromium through WebDriver (selenium with Debian's
chromedriver): loads the page, waits for the first tiles, zooms in once, clicks a pixel and
shift-clicks another, then picks the (theta1, omega1) plane with the axis menus and clicks a
pixel of it, and prints what it saw as JSON (timings in seconds from page load).

Usage: explore.py URL OUTDIR   (screenshots map.png and pendulum.png go to OUTDIR)
"""
import json
import sys
import time

from selenium import webdriver
from selenium.webdriver.chrome.service import Service
from selenium.webdriver.common.action_chains import ActionChains
from selenium.webdriver.common.by import By
from selenium.webdriver.common.keys import Keys
from selenium.webdriver.support.ui import Select, WebDriverWait

url, out = sys.argv[1], sys.argv[2]
options = webdriver.ChromeOptions()
options.binary_location = "/usr/bin/chromium"
for flag in ["--headless", "--no-sandbox", "--disable-gpu", "--disable-dev-shm-usage",
             "--disable-background-networking", "--window-size=872,512"]:
    options.add_argument(flag)
driver = webdriver.Chrome(service=Service("/usr/bin/chromedriver"), options=options)
report = {}
try:
    wait = WebDriverWait(driver, 90, poll_frequency=0.05)
    # The map 512 x 512 (the panel is 360 wide): the first view is the whole turn, one
    # 256 x 256 tile at zoom 0; one zoom step at the centre needs the 4 tiles of zoom 1.
    def viewport(width, height):
        driver.execute_cdp_cmd("Emulation.setDeviceMetricsOverride", {
            "width": width, "height": height, "deviceScaleFactor": 1, "mobile": False})

    # The first view of a 1400 x 900 window (no view in the address): the whole turn fills
    # the map's shorter side, to within Leaflet's quarter zoom step.
    viewport(1400, 900)
    driver.get(url + "#t_max=2")
    wait.until(lambda d: d.execute_script(
        "return window.chaoscope && window.chaoscope.firstView !== null"))
    report["first_fill"] = driver.execute_script("""
        const m = window.chaoscope.map, box = m.getSize(), u = 256;
        const a = m.latLngToContainerPoint([0, 0]), b = m.latLngToContainerPoint([-u, u]);
        return [Math.abs(b.x - a.x), Math.abs(b.y - a.y), box.x, box.y, m.getZoom()];""")
    time.sleep(0.5)  # Leaflet fades new tiles in
    driver.save_screenshot(out + "/first.png")
    driver.get("about:blank")

    viewport(872, 512)
    driver.get(url + "#z=0&cx=0&cy=0&t_max=20")
    wait.until(lambda d: d.execute_script(
        "return window.chaoscope && window.chaoscope.firstView !== null"))
    report["first_view_s"] = driver.execute_script(
        "return window.chaoscope.firstView / 1000")
    box = driver.find_element(By.ID, "map").rect
    report["map_box"] = [int(box["x"]), int(box["y"]), int(box["width"]), int(box["height"])]
    report["status"] = driver.find_element(By.ID, "status").text
    report["kinds"] = driver.execute_script(
        "return [...document.querySelector('select[name=kind]').options].map(o => o.value)")
    driver.save_screenshot(out + "/map.png")

    started = driver.execute_script("""
        const p = window.chaoscope; p.zoomLoads = p.loads; p.tilesAsked = 0;
        p.layer.on('tileloadstart', () => { p.tilesAsked += 1; });
        p.zoomStart = performance.now(); p.map.zoomIn(); return p.zoomStart;""")
    wait.until(lambda d: d.execute_script(
        "const p = window.chaoscope; return p.loads > p.zoomLoads;"))
    report["zoom_step_s"] = driver.execute_script(
        "const p = window.chaoscope; return (p.lastLoad - p.zoomStart) / 1000")
    report["zoom_step_tiles"] = driver.execute_script("return window.chaoscope.tilesAsked")

    # Click the pixel at (2.5, 2.5) rad, which flips early, then shift-click a neighbour.
    def click_at(theta1, theta2, shift=False):
        x, y = driver.execute_script("""
            const p = window.chaoscope, w = 256, t = 2 * Math.PI;
            const pt = p.map.latLngToContainerPoint([(arguments[1] - Math.PI) * w / t,
                                                     (arguments[0] + Math.PI) * w / t]);
            return [pt.x, pt.y];""", theta1, theta2)
        element = driver.find_element(By.ID, "map")
        dx, dy = x - element.rect["width"] / 2, y - element.rect["height"] / 2
        chain = ActionChains(driver)
        if shift:
            chain = chain.key_down(Keys.SHIFT)
        chain = chain.move_to_element_with_offset(element, dx, dy).click()
        if shift:
            chain = chain.key_up(Keys.SHIFT)
        chain.perform()

    viewport(1280, 860)
    # The view's own tiles loaded (a load counted after the move: the data attribute still
    # says 'loaded' from the view before while the zoom animates, and a click then misses).
    driver.execute_script("""const t = 2 * Math.PI, p = window.chaoscope;
        p.viewLoads = p.loads;
        p.map.setView([(1.2 - Math.PI) * 256 / t, (0.9 + Math.PI) * 256 / t], 2)""")
    wait.until(lambda d: d.execute_script(
        "const p = window.chaoscope; return p.loads > p.viewLoads"
        " && document.body.dataset.tiles === 'loaded'"))
    click_at(2.5, 2.5)
    wait.until(lambda d: d.execute_script("return document.body.dataset.pendulum === 'shown'"))
    click_at(2.52, 2.5, shift=True)
    wait.until(lambda d: len(d.find_elements(By.CSS_SELECTOR, "#starts li")) == 2
               and d.execute_script("return document.body.dataset.pendulum === 'shown'"))
    time.sleep(0.5)  # a few animation frames
    report["command"] = driver.find_element(By.ID, "command").text
    report["starts"] = [li.text for li in driver.find_elements(By.CSS_SELECTOR, "#starts li")]
    report["swing_pixels"] = driver.execute_script("""
        const c = document.getElementById('swing');
        const d = c.getContext('2d').getImageData(0, 0, c.width, c.height).data;
        let n = 0; for (let k = 3; k < d.length; k += 4) if (d[k] > 0) n += 1; return n;""")
    report["hash"] = driver.execute_script("return location.hash")
    driver.save_screenshot(out + "/pendulum.png")

    # "Zoom film to here": the command of a zoom from the whole plane to this view.
    driver.find_element(By.ID, "zoom-button").click()
    wait.until(lambda d: d.find_element(By.ID, "zoom-command").text.startswith("chaoscope zoom"))
    report["zoom_command"] = driver.find_element(By.ID, "zoom-command").text
    report["zoom_view"] = driver.execute_script("""const m = window.chaoscope.map;
        return [m.getSize().x, m.getZoom()];""")
    driver.execute_script("document.getElementById('zoom-command').scrollIntoView()")
    driver.save_screenshot(out + "/zoom.png")

    # Another plane through the axis menus: y becomes omega1 (its default range), theta2
    # fixed at 0.4; then a click at (theta1, omega1) = (2.0, 3.0).
    Select(driver.find_element(By.NAME, "y")).select_by_value("omega1")
    wait.until(lambda d: d.execute_script("return document.body.dataset.tiles === 'loaded'"))
    theta2 = driver.find_element(By.NAME, "theta2")
    theta2.clear()
    theta2.send_keys("0.4" + Keys.TAB)
    wait.until(lambda d: "theta2=0.4" in d.execute_script("return window.chaoscope.layer._url")
               and d.execute_script("return document.body.dataset.tiles === 'loaded'"))
    time.sleep(0.5)
    report["plane_tiles"] = driver.execute_script("return window.chaoscope.layer._url")
    report["plane_status"] = driver.find_element(By.ID, "status").text
    report["plane_inputs"] = driver.execute_script("""return ['omega1', 'theta2', 'm2']
        .map(k => [k, document.querySelector(`input[name=${k}]`).disabled])""")
    driver.save_screenshot(out + "/plane.png")
    x, y = driver.execute_script("""
        const p = window.chaoscope.map.latLngToContainerPoint([latOf(3.0), lngOf(2.0)]);
        return [p.x, p.y];""")
    element = driver.find_element(By.ID, "map")
    ActionChains(driver).move_to_element_with_offset(
        element, x - element.rect["width"] / 2, y - element.rect["height"] / 2).click().perform()
    wait.until(lambda d: len(d.find_elements(By.CSS_SELECTOR, "#starts li")) == 1
               and d.execute_script("return document.body.dataset.pendulum === 'shown'"))
    report["plane_starts"] = [li.text for li in driver.find_elements(By.CSS_SELECTOR, "#starts li")]
    report["plane_command"] = driver.find_element(By.ID, "command").text
    report["console_errors"] = [e["message"] for e in driver.get_log("browser")
                                if e["level"] == "SEVERE"]
finally:
    driver.quit()
print(json.dumps(report))
