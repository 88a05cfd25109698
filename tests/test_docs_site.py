"""The documentation site (mkdocs.yml): it builds in strict mode, and real headless Chromium shows it.

``mkdocs build --strict`` fails on a broken link, a missing page or a docstring mkdocstrings cannot read. The
browser test serves the built site on 127.0.0.1 and drives Debian's ``chromium`` through ``chromedriver`` (the
``chromium`` and ``chromium-driver`` packages; .ci/run installs them when missing) with selenium: the env card and
the derivation pages load with no console error, the derivation's math is typeset by the bundled MathJax (SVG,
no CDN), the figures load, and the search box finds a page. Everything runs offline. Without a browser these are
skipped with one line, unless ``AMIGO_GYM_REQUIRE_BROWSER=1`` (.ci/run sets it): then they fail.
"""

from __future__ import annotations

import functools
import http.server
import os
import re
import shutil
import subprocess
import sys
import tempfile
import threading
from collections.abc import Iterator
from pathlib import Path
from typing import Any

import pytest

ROOT = Path(__file__).resolve().parents[1]
CHROMIUM = shutil.which("chromium") or "/usr/bin/chromium"
CHROMEDRIVER = shutil.which("chromedriver") or "/usr/bin/chromedriver"
CHROMIUM_FLAGS = [
    "--headless",
    "--no-sandbox",
    "--disable-gpu",
    "--disable-background-networking",
    "--disable-component-update",
    "--disable-sync",
    "--no-first-run",
    "--window-size=1280,1000",
]


@pytest.fixture(scope="module")
def site() -> Iterator[Path]:
    """The site built by ``mkdocs build --strict`` into a temporary folder."""
    with tempfile.TemporaryDirectory() as tmp:
        out = Path(tmp) / "site"
        env = {**os.environ, "NO_MKDOCS_2_WARNING": "1"}
        r = subprocess.run(
            [sys.executable, "-m", "mkdocs", "build", "--strict", "--site-dir", str(out)],
            cwd=ROOT,
            capture_output=True,
            text=True,
            timeout=120,
            env=env,
        )
        assert r.returncode == 0, r.stdout + r.stderr
        yield out


def test_strict_build_has_every_page_the_api_and_the_local_math_renderer(site: Path) -> None:
    for page in ("index.html", "env_card/index.html", "derivation/index.html", "api/index.html"):
        assert (site / page).is_file(), page
    api = (site / "api/index.html").read_text(encoding="utf-8")
    # generated from the docstrings: the class and a sentence of amigo_gym.envs.amigobot's module docstring
    assert "AmigoBotEnv" in api and "a configuration of the one robot and task" in api
    assert (site / "assets/mathjax/tex-svg-full.js").stat().st_size > 1_000_000
    derivation = (site / "derivation/index.html").read_text(encoding="utf-8")
    assert derivation.count('class="arithmatex"') >= 3
    for html in site.rglob("*.html"):  # the site fetches nothing from elsewhere (offline, no CDN)
        text = html.read_text(encoding="utf-8")
        assert not re.search(r"<(script|link)[^>]+(src|href)=\"https?://", text), html
    assert "env_card" in (site / "search/search_index.json").read_text(encoding="utf-8")


def test_derivation_page_math_is_the_symbolic_modules_output() -> None:
    """The typeset system (29) in docs/derivation.md is what ``symbolic.system_29_latex()`` prints, not a copy by
    hand that could drift."""
    import amigo_gym.tools.symbolic as sym  # sympy: the dev extra

    text = (ROOT / "docs/derivation.md").read_text(encoding="utf-8")
    block = text.split("\\begin{aligned}", 1)[1].split("\\end{aligned}", 1)[0]
    rows = [ln.strip().removesuffix("\\\\").strip() for ln in block.strip().splitlines()]
    lines = [re.sub(r"\s*&&\s*\\text\{\([^)]*\)\}$", "", r).replace("&=", "=") for r in rows]
    tags = [re.search(r"\\text\{\(([^)]*)\)\}", r).group(1) for r in rows]  # type: ignore[union-attr]
    assert lines == sym.system_29_latex()
    assert tags == list(sym.SYSTEM_29_LABELS)


class _QuietHandler(http.server.SimpleHTTPRequestHandler):
    def log_message(self, format: str, *args: Any) -> None:
        pass


@pytest.fixture(scope="module")
def served(site: Path) -> Iterator[str]:
    """The built site over HTTP on 127.0.0.1 (a free port), as a browser would read a deployed site."""
    handler = functools.partial(_QuietHandler, directory=str(site))
    server = http.server.ThreadingHTTPServer(("127.0.0.1", 0), handler)
    thread = threading.Thread(target=server.serve_forever, daemon=True)
    thread.start()
    try:
        yield f"http://127.0.0.1:{server.server_address[1]}"
    finally:
        server.shutdown()
        server.server_close()


@pytest.fixture(scope="module")
def browser() -> Iterator[Any]:
    from selenium import webdriver  # the docs extra (in dev)
    from selenium.webdriver.chrome.service import Service

    missing = [exe for exe in (CHROMIUM, CHROMEDRIVER) if not Path(exe).is_file()]
    if missing:  # a fresh clone without a browser skips; .ci/run (which installs one) sets REQUIRE_BROWSER: fails
        why = f"no {' or '.join(missing)} (apt-get install chromium chromium-driver; .ci/run does)"
        if os.environ.get("AMIGO_GYM_REQUIRE_BROWSER") == "1":
            pytest.fail(f"{why}, and AMIGO_GYM_REQUIRE_BROWSER=1")
        pytest.skip(why)
    with tempfile.TemporaryDirectory() as profile:
        options = webdriver.ChromeOptions()
        options.binary_location = CHROMIUM
        for flag in [*CHROMIUM_FLAGS, f"--user-data-dir={profile}"]:
            options.add_argument(flag)
        options.set_capability("goog:loggingPrefs", {"browser": "ALL"})
        driver = webdriver.Chrome(options=options, service=Service(executable_path=CHROMEDRIVER))
        driver.set_page_load_timeout(30)
        driver.set_script_timeout(30)
        try:
            yield driver
        finally:
            driver.quit()


def _console_errors(driver: Any) -> list[str]:
    return [e["message"] for e in driver.get_log("browser") if e["level"] == "SEVERE"]


def _images(driver: Any) -> list[tuple[str, int]]:
    js = "return Array.from(document.querySelectorAll('article img')).map(i => [i.src, i.naturalWidth]);"
    return [tuple(x) for x in driver.execute_script(js)]


def test_env_card_page_loads_with_its_figure_and_no_console_error(browser: Any, served: str) -> None:
    browser.get_log("browser")  # drop anything logged before
    browser.get(served + "/env_card/")
    assert browser.title.startswith("Environment card")
    assert "AmigoBot-v0" in browser.find_element("css selector", "article h1").text
    images = _images(browser)
    assert images and all(width > 0 for _, width in images), images  # the figure is shown, not a broken image
    assert _console_errors(browser) == []


def test_derivation_page_renders_its_math_with_no_console_error(browser: Any, served: str) -> None:
    browser.get_log("browser")
    browser.get(served + "/derivation/")
    # wait for MathJax's typesetting to finish (its startup promise), then inspect what it produced
    state = browser.execute_async_script(
        """const done = arguments[arguments.length - 1];
        const wait = () => (window.MathJax && MathJax.startup && MathJax.startup.promise)
            ? MathJax.startup.promise.then(() => done('typeset'), e => done('error: ' + e))
            : setTimeout(wait, 50);
        wait();"""
    )
    assert state == "typeset"
    info = browser.execute_script(
        """const spans = Array.from(document.querySelectorAll('.arithmatex'));
        return {
          spans: spans.length,
          rendered: spans.filter(s => s.querySelector('mjx-container svg')).length,
          sizes: spans.map(s => { const r = s.getBoundingClientRect(); return [r.width, r.height]; }),
          errors: document.querySelectorAll('mjx-merror, [data-mjx-error]').length,
          raw: spans.filter(s => /\\\\begin|\\\\frac/.test(s.innerText)).length,
          display: document.querySelectorAll('mjx-container[display="true"]').length,
        };"""
    )
    assert info["spans"] >= 3 and info["rendered"] == info["spans"], info  # every formula became an SVG
    assert info["display"] >= 2 and info["errors"] == 0 and info["raw"] == 0, info
    assert all(w > 0 and h > 0 for w, h in info["sizes"]), info
    assert _console_errors(browser) == []


def test_search_box_finds_the_env_card(browser: Any, served: str) -> None:
    from selenium.common.exceptions import StaleElementReferenceException
    from selenium.webdriver.common.by import By
    from selenium.webdriver.support.ui import WebDriverWait

    def result_links(d: Any) -> list[str]:
        """The hrefs of the search results; [] (wait on) while the list is being re-rendered."""
        try:
            hrefs = [a.get_attribute("href") or "" for a in d.find_elements(By.CSS_SELECTOR, ".md-search-result__link")]
        except StaleElementReferenceException:
            return []
        return hrefs if any("env_card" in h for h in hrefs) else []

    browser.get(served + "/")
    box = browser.find_element(By.CSS_SELECTOR, "input.md-search__input")  # the search box in the header
    box.click()
    box.send_keys("observation")
    links = WebDriverWait(browser, 20).until(result_links)
    assert any("env_card" in href for href in links), links
    assert _console_errors(browser) == []
