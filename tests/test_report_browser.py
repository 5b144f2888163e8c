"""The report in a real headless browser (issue #17): Debian's Chromium renders report.html, every image
decodes, nothing overflows the page sideways at a laptop's and a phone's width, the configurations are
folded away; the screenshots are kept for a person to look at (pytest's tmp directory)."""

import importlib.util
import shutil

import pytest

CHROMIUM, DRIVER = shutil.which("chromium") or shutil.which("chromium-browser"), shutil.which("chromedriver")
HOW = ("needs Chromium and its driver (Debian: apt install chromium chromium-driver) and selenium "
       "(pip install selenium; in the test extra)")
pytestmark = pytest.mark.skipif(not (CHROMIUM and DRIVER and importlib.util.find_spec("selenium")), reason=HOW)

CHECK = """
const images = Array.from(document.images);
return {
  images: images.length,
  broken: images.filter(i => !(i.complete && i.naturalWidth > 0)).map(i => i.alt),
  page_overflow: document.documentElement.scrollWidth - document.documentElement.clientWidth,
  wide: Array.from(document.querySelectorAll('body *')).filter(e => {
      const r = e.getBoundingClientRect(); return r.right > document.documentElement.clientWidth + 1
          && getComputedStyle(e).position !== 'fixed' && !e.closest('details:not([open])') && !e.closest('.wrap');
  }).map(e => e.tagName + '.' + e.className).slice(0, 5),
  details: document.querySelectorAll('details').length,
  open_details: document.querySelectorAll('details[open]').length,
  headings: Array.from(document.querySelectorAll('h2')).map(h => h.textContent),
};
"""


@pytest.fixture(scope="module")
def browser():
    from selenium import webdriver
    from selenium.webdriver.chrome.service import Service

    options = webdriver.ChromeOptions()
    options.binary_location = CHROMIUM
    for flag in ("--headless=new", "--no-sandbox", "--disable-gpu", "--disable-quic", "--no-first-run",
                 "--disable-background-networking", "--disable-component-update", "--disable-sync",
                 "--disable-dev-shm-usage"):
        options.add_argument(flag)
    driver = webdriver.Chrome(service=Service(DRIVER), options=options)
    yield driver
    driver.quit()


@pytest.mark.parametrize("width", [1280, 420])
def test_the_report_renders_whole(browser, demo_run, tmp_path, width):
    from radioslam.pipeline import report_stage

    out, _ = demo_run
    report = report_stage(out)
    browser.set_window_size(width, 1000)
    browser.get(report.resolve().as_uri())
    state = browser.execute_script(CHECK)
    assert state["images"] >= 2 and state["broken"] == []
    assert state["page_overflow"] <= 0 and state["wide"] == [], state
    assert state["details"] == 4 and state["open_details"] == 0  # configurations folded away
    assert state["headings"][:3] == ["Results", "Map (the paper's Fig. 6)", "Along the run"]
    text = browser.find_element("tag name", "body").text
    assert "ATE RMSE, SLAM" in text and "command" in text and "radioslam" in text
    browser.set_window_size(width, 4200)
    browser.save_screenshot(str(tmp_path / f"report-{width}.png"))
