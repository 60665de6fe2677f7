"""Headless Chromium for the browser tests, through WebDriver (selenium with Debian's
chromedriver): with its software WebGPU adapter (SwiftShader), or without WebGPU."""
from selenium import webdriver
from selenium.webdriver.chrome.service import Service


def start(webgpu=True):
    """A new headless Chromium; the caller quits it."""
    options = webdriver.ChromeOptions()
    options.binary_location = "/usr/bin/chromium"
    flags = ["--headless=new", "--no-sandbox", "--disable-dev-shm-usage",
             "--disable-background-networking"]
    flags += ["--enable-unsafe-webgpu", "--use-webgpu-adapter=swiftshader"] if webgpu \
        else ["--disable-gpu"]
    for flag in flags:
        options.add_argument(flag)
    return webdriver.Chrome(service=Service("/usr/bin/chromedriver"), options=options)
