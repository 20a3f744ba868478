"""Drive a studio page in headless Chromium, for the browser tests and the latency benchmark
(``scripts/bench_studio.py``); imported by test modules as ``studio_driver``.

Needs selenium (the ``test`` extra) and Debian's ``chromium`` + ``chromium-driver``. Nothing is
downloaded: the driver is /usr/bin/chromedriver, Selenium Manager's statistics are off, and
Chromium starts with a fresh, empty profile and its background networking disabled.

::

    with StudioProcess() as studio, chromium(download_dir) as driver:
        page = StudioPage(driver, studio.url)
        page.wait_idle()
        page.set_field("blades", "4")
"""

from __future__ import annotations

import contextlib
import functools
import os
import re
import signal
import subprocess
import sys
import tempfile
import time
from collections.abc import Callable, Iterator, Sequence
from pathlib import Path
from typing import Any, Self, TypeVar

from torus_cad.studio.layout import field_id

CHROMEDRIVER = Path("/usr/bin/chromedriver")
CHROMIUM = Path("/usr/bin/chromium")

#: Chromium switches for a headless run on a machine without a GPU, a display or the internet
#: (SwiftShader: WebGL on the CPU, for the studio's 3D view).
CHROMIUM_ARGUMENTS = (
    "--headless=new",
    "--no-sandbox",
    "--disable-gpu",
    "--disable-quic",
    "--no-first-run",
    "--disable-background-networking",
    "--disable-component-update",
    "--disable-sync",
    "--disable-dev-shm-usage",
    "--enable-unsafe-swiftshader",
)

#: Seconds to wait for the studio to start (its first start imports the kernel on a busy machine).
START_TIMEOUT_S = 180.0

T = TypeVar("T")

_URL = re.compile(r"open (http://\S+/)")


class StudioProcess:
    """``python -m torus_cad studio [ARGS] --port 0`` in its own process group; ``url`` once it
    serves."""

    def __init__(self, arguments: Sequence[str] = (), cwd: Path | None = None) -> None:
        self.arguments = list(arguments)
        self.cwd = cwd
        self.url = ""
        self.output: list[str] = []
        self._process: subprocess.Popen[str] | None = None

    def __enter__(self) -> Self:
        command = [sys.executable, "-m", "torus_cad", "studio", *self.arguments, "--port", "0"]
        self._process = subprocess.Popen(
            command,
            cwd=self.cwd,
            stdout=subprocess.PIPE,
            stderr=subprocess.STDOUT,
            text=True,
            start_new_session=True,
        )
        deadline = time.monotonic() + START_TIMEOUT_S
        assert self._process.stdout is not None
        while time.monotonic() < deadline:
            line = self._process.stdout.readline()
            if not line:
                raise RuntimeError(f"the studio exited before serving:\n{''.join(self.output)}")
            self.output.append(line)
            match = _URL.search(line)
            if match:
                self.url = match.group(1)
                return self
        self.__exit__(None, None, None)
        raise TimeoutError(
            f"the studio did not start within {START_TIMEOUT_S} s:\n{''.join(self.output)}"
        )

    def __exit__(self, *_: object) -> None:
        process = self._process
        if process is None:
            return
        with contextlib.suppress(ProcessLookupError):
            os.killpg(process.pid, signal.SIGTERM)  # the studio, its forkserver and any build
        try:
            process.wait(timeout=20)
        except subprocess.TimeoutExpired:
            with contextlib.suppress(ProcessLookupError):
                os.killpg(process.pid, signal.SIGKILL)
            process.wait(timeout=20)
        if process.stdout is not None:
            self.output.append(process.stdout.read())
            process.stdout.close()


@contextlib.contextmanager
def chromium(download_dir: Path, size: tuple[int, int] = (1500, 950)) -> Iterator[Any]:
    """A headless Chromium (selenium WebDriver) saving downloads into ``download_dir``."""
    os.environ.setdefault("SE_AVOID_STATS", "true")  # Selenium Manager: no usage statistics
    from selenium import webdriver
    from selenium.webdriver.chrome.service import Service

    options = webdriver.ChromeOptions()
    options.binary_location = str(CHROMIUM)
    with tempfile.TemporaryDirectory(prefix="torus-cad-chromium-") as profile:
        for argument in (
            *CHROMIUM_ARGUMENTS,
            f"--user-data-dir={profile}",
            f"--window-size={size[0]},{size[1]}",
        ):
            options.add_argument(argument)
        options.add_experimental_option(
            "prefs",
            {
                "download.default_directory": str(download_dir),
                "download.prompt_for_download": False,
                "download.directory_upgrade": True,
                "safebrowsing.enabled": False,
            },
        )
        driver = webdriver.Chrome(service=Service(str(CHROMEDRIVER)), options=options)
        try:
            yield driver
        finally:
            driver.quit()


# Records, in the page, when a change was typed and when the preview and the exact solid were shown.
_LATENCY_PROBE = """
window.__studioTimes = {input: null, preview: null, exact: null};
document.addEventListener('input', () => {
  window.__studioTimes = {input: performance.now(), preview: null, exact: null};
}, true);
for (const [id, key] of [['preview-stamp', 'preview'], ['exact-stamp', 'exact']]) {
  new MutationObserver(() => {
    const times = window.__studioTimes;
    if (times.input !== null && times[key] === null) { times[key] = performance.now(); }
  }).observe(document.getElementById(id), {childList: true, characterData: true, subtree: true});
}
"""


class StudioPage:
    """The studio page in a WebDriver, with waits that fail with the page's state in the message."""

    def __init__(self, driver: Any, url: str, timeout_s: float = 120.0) -> None:
        self.driver, self.timeout_s = driver, timeout_s
        driver.get(url)
        self.wait(
            lambda: self.text("status") in ("exact", "preview", "refused", "failed"),
            "the page to load",
        )

    # -- reading -----------------------------------------------------------------------------------
    def element(self, element_id: str) -> Any:
        from selenium.webdriver.common.by import By

        return self.driver.find_element(By.ID, element_id)

    def exists(self, element_id: str) -> bool:
        from selenium.webdriver.common.by import By

        return bool(self.driver.find_elements(By.ID, element_id))

    def text(self, element_id: str) -> str:
        from selenium.common.exceptions import (
            NoSuchElementException,
            StaleElementReferenceException,
        )

        try:
            return self.element(element_id).text.strip()
        except (NoSuchElementException, StaleElementReferenceException):
            return ""

    def field_value(self, key: str) -> str:
        return self.element(field_id(key)).get_attribute("value") or ""

    def stamp(self, element_id: str) -> int:
        """A hidden counter of the page (``preview-stamp``, ``exact-stamp``)."""
        return int(self.element(element_id).get_attribute("textContent") or 0)

    def message_of(self, element_id: str) -> str:
        """The text of the Vuetify input holding ``element_id``: its label and messages (error or
        hint)."""
        from selenium.common.exceptions import NoSuchElementException
        from selenium.webdriver.common.by import By

        try:
            container = self.element(element_id).find_element(
                By.XPATH,
                "./ancestor::div[contains(concat(' ', "
                "normalize-space(@class), ' '), ' v-input ')][1]",
            )
        except NoSuchElementException:
            return ""
        return container.text

    def field_message(self, key: str) -> str:
        """The text under a parameter's input (its error message or hint), or its vector's error
        line."""
        return self.text(field_id(key) + "-error") or self.message_of(field_id(key))

    def change(self, key: str, text: str) -> None:
        """Enter ``text`` into a field and wait until the exact solid of the new design is shown."""
        if self.field_value(key) == text and self.idle():
            return
        before = self.stamp("exact-stamp")
        self.set_field(key, text)
        self.wait(
            lambda: self.stamp("exact-stamp") > before and self.idle(),
            f"the exact solid after {key} = {text}",
        )

    def wait(self, condition: Callable[[], T], what: str, timeout_s: float | None = None) -> T:
        """Poll ``condition`` until it returns something truthy; fail naming ``what`` and the page
        state."""
        from selenium.common.exceptions import StaleElementReferenceException

        deadline = time.monotonic() + (self.timeout_s if timeout_s is None else timeout_s)
        while True:
            try:
                result = condition()
            # Vue re-rendered the element between finding and reading it
            except StaleElementReferenceException:
                result = None
            if result:
                return result
            if time.monotonic() > deadline:
                raise TimeoutError(
                    f"timed out waiting for {what}; status {self.text('status')!r}, "
                    f"refusal {self.text('refusal')!r}, failure {self.text('failure')!r}"
                )
            time.sleep(0.05)

    def idle(self) -> bool:
        """The exact solid is on screen and its files are ready."""
        from selenium.common.exceptions import (
            NoSuchElementException,
            StaleElementReferenceException,
        )

        try:
            return self.text("status") == "exact" and self.element("download-step").is_enabled()
        # the buttons appear with the files
        except (NoSuchElementException, StaleElementReferenceException):
            return False

    def wait_idle(self) -> None:
        self.wait(self.idle, "the exact solid and its files")

    # -- acting ------------------------------------------------------------------------------------
    def set_field(self, key: str, text: str) -> None:
        """Replace a field's text as a user would: select all, type."""
        from selenium.webdriver.common.keys import Keys

        field = self.element(field_id(key))
        field.send_keys(Keys.CONTROL, "a")
        field.send_keys(text)

    def choose(self, key: str, option: str) -> None:
        """Pick ``option`` in a parameter's menu (a choice), as a user would: open it, click the
        item."""
        from selenium.webdriver.common.by import By

        field = self.element(field_id(key))
        control = field.find_element(
            By.XPATH,
            "./ancestor::div[contains(concat(' ', normalize-space(@class), ' '), ' v-field ')][1]",
        )
        self.driver.execute_script("arguments[0].scrollIntoView({block: 'center'});", control)
        self._click(control)
        xpath = (
            "//div[contains(@class, 'v-overlay--active')]//div[@role "
            f"= 'option'][normalize-space(.) = '{option}']"
        )
        item = self.wait(
            lambda: self.driver.find_elements(By.XPATH, xpath), f"the menu item {option!r}"
        )[0]
        self._click(item)

    def _click(self, element: Any) -> None:
        """Click ``element``; while an overlay is still animating over it (Vuetify's menus fade in
        and out), the browser's click hits the overlay, so the click event is sent to the element
        itself."""
        from selenium.common.exceptions import (
            ElementClickInterceptedException,
            ElementNotInteractableException,
        )

        try:
            element.click()
        except (ElementClickInterceptedException, ElementNotInteractableException):
            self.driver.execute_script("arguments[0].click();", element)

    def open_all_groups(self) -> None:
        """Expand every group of the parameters panel (only the first few start open), one at a
        time."""
        from selenium.webdriver.common.by import By

        closed = ".v-expansion-panel:not(.v-expansion-panel--active) > .v-expansion-panel-title"
        for _ in range(100):
            titles = self.driver.find_elements(By.CSS_SELECTOR, closed)
            if not titles:
                return
            self.driver.execute_script("arguments[0].click();", titles[0])
            self.wait(functools.partial(self._fewer, closed, len(titles)), "a group to open")

    def _fewer(self, selector: str, count: int) -> bool:
        from selenium.webdriver.common.by import By

        return len(self.driver.find_elements(By.CSS_SELECTOR, selector)) < count

    def click(self, element_id: str) -> None:
        """Click the element ``element_id`` (a button) as a user would."""
        element = self.element(element_id)
        self.driver.execute_script("arguments[0].scrollIntoView({block: 'center'});", element)
        self._click(element)

    def view_pixels(self) -> Any:
        """The 3D view's pixels as an ``(h, w, 3)`` float array, 0..255."""
        import io

        import numpy as np
        from PIL import Image

        box = self.element("view").rect
        image = Image.open(io.BytesIO(self.driver.get_screenshot_as_png())).convert("RGB")
        return np.asarray(
            image.crop(
                (
                    int(box["x"]),
                    int(box["y"]),
                    int(box["x"] + box["width"]),
                    int(box["y"] + box["height"]),
                )
            ),
            dtype=float,
        )

    def drag_view(self, dx: int, dy: int, steps: int = 10) -> None:
        """Drag across the 3D view with the left button (orbit), in ``steps`` moves as a hand
        would."""
        from selenium.webdriver.common.action_chains import ActionChains

        chain = (
            ActionChains(self.driver, duration=50)
            .move_to_element(self.element("view"))
            .click_and_hold()
        )
        for _ in range(steps):
            chain = chain.move_by_offset(dx // steps, dy // steps)
        chain.release().perform()

    def start_latency_probe(self) -> None:
        self.driver.execute_script(_LATENCY_PROBE)

    def latencies_ms(self) -> dict[str, float | None]:
        """Milliseconds from the last typed change to the preview's and the exact solid's
        display."""
        times = self.driver.execute_script("return window.__studioTimes;")
        start = times["input"]
        return {
            key: (None if times[key] is None or start is None else times[key] - start)
            for key in ("preview", "exact")
        }

    def screenshot(self, path: Path) -> None:
        """Save the page as PNG, scrolled to the top (clicks may have scrolled it)."""
        self.driver.execute_script(
            "window.scrollTo(0, 0); for (const element of document.querySelectorAll("
            "'#readouts-column, .v-navigation-drawer__content')) { element.scrollTop = 0; }"
        )
        path.parent.mkdir(parents=True, exist_ok=True)
        self.driver.save_screenshot(str(path))


def wait_for_download(
    directory: Path, suffix: str, timeout_s: float = 60.0, known: Sequence[Path] = ()
) -> Path:
    """The first new, complete file ending in ``suffix`` in ``directory``."""
    deadline = time.monotonic() + timeout_s
    while time.monotonic() < deadline:
        done = [path for path in directory.glob(f"*{suffix}") if path not in known]
        if done and not list(directory.glob("*.crdownload")):
            return done[0]
        time.sleep(0.1)
    raise TimeoutError(f"no {suffix} file was downloaded into {directory} within {timeout_s} s")
