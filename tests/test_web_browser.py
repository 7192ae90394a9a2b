"""``uasnav serve`` in a real headless Chromium (Debian's ``chromium`` driven by Playwright through
``executable_path``; ``make setup`` installs it). One server and one browser for the module.

Every request a page makes that is not to the app is blocked and recorded, and each test ends
by asserting there was none: the application works offline. Screenshots at desktop and phone
widths are written to ``build/screenshots/``.
"""

from __future__ import annotations

import io
import json
import re
import shutil
import subprocess
import unicodedata
from collections import Counter
from collections.abc import Iterator
from pathlib import Path

import pypdf
import pytest
from click.testing import CliRunner

from uasnav.cli import main
from uasnav.io.plans import plan_route, read_plan, write_plan
from uasnav.trajectory.features import wind_vector
from uasnav.web.context import plain
from uasnav.web.default_model import default_model
from uasnav.web.process import Server, running_server, uasnav_command

ROOT = Path(__file__).resolve().parents[1]
SHOTS = ROOT / "build" / "screenshots"
DESKTOP = {"width": 1366, "height": 900}
PHONE = {"width": 390, "height": 844}
#: The thesis' precision-agriculture scenario (Table 22, §5.2.3.6) as typed in the form.
THESIS = {
    "range": "1500",
    "resolution": "0.05",
    "image_size": "70x70",
    "altitude": "50",
    "wind": "5",
}
THESIS_SELECTS = {"mission": "precision-agriculture", "imagery": "multispectral", "order_by": "cost"}


def chromium_path() -> str:
    found = shutil.which("chromium") or shutil.which("chromium-browser")
    assert found, "chromium is not installed: run `make setup` (apt-get install chromium)"
    return found


@pytest.fixture(scope="module")
def server() -> Iterator[Server]:
    with running_server() as s:
        yield s


@pytest.fixture(scope="module")
def browser() -> Iterator[object]:
    from playwright.sync_api import sync_playwright

    with sync_playwright() as p:
        b = p.chromium.launch(executable_path=chromium_path())
        yield b
        b.close()


class Pages:
    """Opens pages that may only talk to the app; records any other request."""

    def __init__(self, browser, server: Server) -> None:  # type: ignore[no-untyped-def]
        self.browser, self.server = browser, server
        self.outside: list[str] = []
        self.contexts: list[object] = []

    def new(self, viewport: dict[str, int] = DESKTOP, **options: object):  # type: ignore[no-untyped-def]
        """A page at ``viewport``; ``options`` go to the browser context (``has_touch`` …)."""
        ctx = self.browser.new_context(viewport=viewport, accept_downloads=True, **options)
        self.contexts.append(ctx)
        base = self.server.url + "/"

        def guard(route):  # type: ignore[no-untyped-def]
            url = route.request.url
            if url.startswith(base) or url == self.server.url:
                route.continue_()
            else:
                self.outside.append(url)
                route.abort()

        ctx.route("**/*", guard)
        page = ctx.new_page()
        page.set_default_timeout(60_000)
        return page


@pytest.fixture
def pages(browser, server) -> Iterator[Pages]:  # type: ignore[no-untyped-def]
    p = Pages(browser, server)
    yield p
    for c in p.contexts:
        c.close()
    assert p.outside == [], f"requests left the app: {p.outside}"


def shot(page, name: str) -> None:  # type: ignore[no-untyped-def]
    SHOTS.mkdir(parents=True, exist_ok=True)
    page.screenshot(path=str(SHOTS / f"{name}.png"), full_page=True)


def landed(page, landing: str = "results") -> None:  # type: ignore[no-untyped-def]
    """Wait for the answer page of a run and assert it landed on ``#landing`` (the focus).

    The page's deferred script (table sorting, the landing focus) has run by DOMContentLoaded;
    the answer's markup is there before it, so waiting for the element alone races it."""
    page.wait_for_selector(f"#{landing}")
    page.wait_for_load_state("domcontentloaded")
    assert page.evaluate("document.activeElement.id") == landing


def assert_route_labels_inside(page) -> None:  # type: ignore[no-untyped-def]
    """Every waypoint label of the route drawing lies inside it (a label past its edge is cut)."""
    cut = page.evaluate(
        """() => { const svg = document.querySelector("#prediction figure.route svg");
          const w = svg.viewBox.baseVal.width;
          return [...svg.querySelectorAll("text.wpl")].map((t) => [t.textContent, t.getBBox()])
            .filter(([, b]) => b.x < 0 || b.x + b.width > w).map(([s]) => s); }"""
    )
    assert cut == [], cut


def open_advanced(page) -> None:  # type: ignore[no-untyped-def]
    """Unfold the form's "Advanced" part (folded by default)."""
    if page.get_attribute("#advanced", "open") is None:
        page.click("#advanced-toggle")


def fill_thesis(page) -> None:  # type: ignore[no-untyped-def]
    open_advanced(page)
    for name, value in THESIS_SELECTS.items():
        page.select_option(f"#f-{name}", value)
    for name, value in THESIS.items():
        page.fill(f"#f-{name}", value)


def cli_select() -> dict:
    argv = ["select", "--json"]
    for k, v in {**THESIS, **THESIS_SELECTS}.items():
        argv += ["--" + k.replace("_", "-"), v]
    out = subprocess.run([*uasnav_command(), *argv], capture_output=True, check=True, timeout=120)
    return json.loads(out.stdout)


def test_thesis_scenario_matches_the_cli(pages, server) -> None:
    expected = cli_select()
    for viewport, tag in ((DESKTOP, "desktop"), (PHONE, "phone")):
        page = pages.new(viewport)
        page.goto(server.url + "/")
        shot(page, f"select-form-{tag}")
        fill_thesis(page)
        page.click("#select-form button[type=submit]")
        landed(page)
        # ranked table: every row, in order, as `uasnav select --json` ranks them
        rows = page.locator("#ranking tbody tr")
        got = [
            (rows.nth(i).locator("td").nth(1).inner_text(), rows.nth(i).locator("td").nth(2).inner_text())
            for i in range(rows.count())
        ]
        assert got == [(r["uas"], r["camera"]) for r in expected["ranking"]]
        first_score = rows.nth(0).locator("td").nth(3).inner_text()
        assert float(first_score) == pytest.approx(expected["ranking"][0]["score"], abs=5e-4)
        # feasible lists and the equipment with its necessary marks
        assert page.locator("#feasible-uas li").all_inner_texts() == expected["feasible_uas"]
        assert page.locator("#feasible-cameras li").all_inner_texts() == expected["feasible_cameras"]
        items = page.locator("dl.equipment li").all_inner_texts()
        assert len(items) == len(expected["equipment"])
        for text, e in zip(items, expected["equipment"], strict=True):
            assert (
                text.upper().startswith("NECESSARY" if e["necessary"] else "OPTIONAL") and e["name"] in text
            )
        assert page.locator("#rejections tbody tr").count() == len(expected["rejections"])
        assert page.locator("figure.plot").count() == 4  # Figure 74, one per scored parameter
        shot(page, f"select-results-{tag}")
        # no sideways scrolling of the page at any width (wide tables scroll in their box)
        assert page.evaluate("document.documentElement.scrollWidth") <= viewport["width"]


def test_ranking_sorts_and_downloads(pages, server, tmp_path) -> None:
    page = pages.new()
    page.goto(server.url + "/")
    page.click("#select-form button[type=submit]")
    landed(page)
    page.click("#ranking th:has-text('Cost (USD)')")
    costs = [
        float(x.replace(",", "")) for x in page.locator("#ranking tbody tr td:nth-child(7)").all_inner_texts()
    ]
    assert costs == sorted(costs)
    with page.expect_download() as d:
        page.click("a:has-text('JSON')")
    data = json.loads(Path(d.value.path()).read_text())
    assert data["ranking"] and data["mission"] == "precision-agriculture"
    # print: the authorisation summary (the document `select --summary` writes), one page
    summary = page.locator(".auth-summary").inner_text()
    page.emulate_media(media="print")
    assert not page.locator("#select-form").is_visible() and not page.locator("header.top").is_visible()
    assert not page.locator("#ranking").is_visible() and page.locator(".auth-summary").is_visible()
    assert page.locator("main").inner_text().strip() == summary.strip()  # nothing else printed
    pdf = pypdf.PdfReader(io.BytesIO(page.pdf(format="A4", print_background=True)))
    assert len(pdf.pages) == 1
    printed = " ".join(pdf.pages[0].extract_text().split())
    # the same document as the CLI's, opened on its own
    out = tmp_path / "summary.html"
    argv = ["select", "--summary", str(out)]
    subprocess.run([*uasnav_command(), *argv], capture_output=True, check=True, timeout=120)
    alone = pages.new()
    alone.set_content(out.read_text())
    # ... in the form's words: the "from" column names fields where the CLI names its options
    cli = plain(alone.locator(".auth-summary").inner_text())
    assert " ".join(cli.split()) == " ".join(summary.split())

    # every character of the summary is on the printed page: nothing clipped or pushed off it
    # (the PDF's text comes out in two columns and with ligatures, so compare as multisets)
    def chars(text: str) -> Counter[str]:
        return Counter(c for c in unicodedata.normalize("NFKC", text) if not c.isspace())

    assert not chars(summary) - chars(printed), chars(summary) - chars(printed)
    assert "Verdict:" in printed and "SORA 2.5" in printed


def test_bad_value_is_shown_beside_its_field(pages, server) -> None:
    page = pages.new()
    page.goto(server.url + "/")
    page.fill("#f-range", "-5")
    page.fill("#f-altitude", "abc")
    page.press("#f-altitude", "Tab")  # the script checks on leaving the field
    assert page.locator("#e-altitude").inner_text().startswith("altitude:")
    page.click("#select-form button[type=submit]")
    page.wait_for_selector(".field.invalid")
    assert page.locator("#e-range").inner_text() == "range: -5 is not >= 1"
    assert page.locator("#e-altitude").inner_text().startswith("altitude: ")
    assert page.locator("#f-range").input_value() == "-5"
    assert page.locator("#results").count() == 0
    assert page.locator("#e-wind").inner_text() == ""
    shot(page, "select-errors-desktop")


def test_keyboard_only(pages, server) -> None:
    """The run button is a few Tab presses away (the short form; "Advanced" folded); Enter on
    "Advanced" unfolds it and Tab then reaches every field in order, typing fills them, Enter
    submits, and the focus lands on the results."""
    page = pages.new()
    page.goto(server.url + "/")
    core = page.eval_on_selector_all(
        "#select-form fieldset.core input:not([type=hidden]), #select-form fieldset.core select",
        "els => els.map(e => e.id)",
    )
    presses = 1
    page.keyboard.press("Tab")  # the skip link
    while page.evaluate("document.activeElement.type") != "submit" and presses < 40:
        page.keyboard.press("Tab")
        presses += 1
    # the skip link, the 4 menu links and the 4 data links of the lead, the core fields,
    # "Advanced", then the button
    assert presses <= 1 + 4 + 4 + len(core) + 2, f"{presses} Tab presses to the run button"
    page.goto(server.url + "/")
    order = page.eval_on_selector_all(
        "#select-form input:not([type=hidden]), #select-form select, #select-form button",
        "els => els.map(e => e.id || e.type)",
    )
    seen: list[str] = []
    page.keyboard.press("Tab")
    assert page.evaluate("document.activeElement.className") == "skip"
    for _ in range(80):
        page.keyboard.press("Tab")
        active = page.evaluate("document.activeElement.id || document.activeElement.type")
        if active == "f-range":
            page.keyboard.press("Control+A")
            page.keyboard.type("800")
        if active == "f-top":
            page.keyboard.press("Control+A")
            page.keyboard.type("3")
        if active == "f-rain":
            page.keyboard.press("Space")
        if active == "advanced-toggle":
            page.keyboard.press("Enter")
        if active in order:
            seen.append(active)
        if active == "submit":
            break
    assert seen == order, "Tab order differs from the form's order"
    with page.expect_navigation():
        page.keyboard.press("Enter")
    landed(page)
    assert 0 < page.locator("#ranking tbody tr").count() <= 3
    facts = page.locator(".facts").first.inner_text()
    assert "range 800 m" in facts and "rain" in facts
    # the ranking's headers sort from the keyboard too
    page.focus("#ranking th:has-text('Score')")
    page.keyboard.press("Enter")
    assert page.get_attribute("#ranking th:has-text('Score')", "aria-sort") == "ascending"


def predicted(page, server, plan: Path, **fields: str):  # type: ignore[no-untyped-def]
    """``page`` with the trajectory form sent for ``plan`` and ``fields`` (form names)."""
    page.goto(server.url + "/trajectory")
    page.set_input_files("#t-plan", str(plan))
    for name, value in fields.items():
        page.fill(f"#t-{name}", value)
    page.click("#trajectory-form button[type=submit]")
    landed(page, "prediction")
    return page


def route_page_fits(page, name: str, viewport: dict[str, int]) -> None:  # type: ignore[no-untyped-def]
    """Screenshot ``name``; every route label inside the drawing, nothing scrolls sideways."""
    shot(page, name)
    assert_route_labels_inside(page)
    assert page.evaluate("document.documentElement.scrollWidth") <= viewport["width"]


def downloaded_lines(page, link: str) -> list[str]:  # type: ignore[no-untyped-def]
    """The lines of the file the link named ``link`` downloads."""
    with page.expect_download() as d:
        page.click(f"a:has-text('{link}')")
    return Path(d.value.path()).read_text().splitlines()


def test_plan_upload_gives_the_predicted_times(pages, server, tmp_path) -> None:
    import pymap3d

    from uasnav.trajectory.simulator import phantom4_plans

    ne = phantom4_plans()["B"]
    lat, lon, _ = pymap3d.ned2geodetic(ne[:, 0], ne[:, 1], 0.0, 47.3977, 8.5456, 50.0)
    csv = tmp_path / "b.csv"
    csv.write_text("lat,lon,alt\n" + "".join(f"{a:.9f},{b:.9f},50\n" for a, b in zip(lat, lon, strict=True)))
    plan = tmp_path / "b.plan"
    write_plan(read_plan(csv), plan)  # a QGroundControl .plan
    route, _ = plan_route(read_plan(plan))
    ref = default_model().predict(route, wind_vector(2.78, 22.5), 3.33)
    flown = cli_mission(plan)
    for viewport, tag in ((DESKTOP, "desktop"), (PHONE, "phone")):
        page = predicted(pages.new(viewport), server, plan, wind_speed="2.78", wind_from="22.5", speed="3.33")
        times = [
            float(x)
            for x in page.eval_on_selector_all(
                "#waypoints td[data-time]", "els => els.map(e => e.dataset.time)"
            )
        ]
        assert times == pytest.approx(list(ref.waypoint_times_s), abs=1e-6)
        # a .plan is a mission: its ETA is the autopilot's (`trajectory mission`), the element
        # model's stands beside it
        assert float(page.get_attribute("#element-eta", "data-eta")) == pytest.approx(ref.eta_s)
        assert float(page.get_attribute("#eta", "data-eta")) == flown["eta_s"]
        assert page.locator("#mission-items td[data-arrive]").count() == len(flown["items"])
        low = page.locator("#elements tbody tr.low").count()
        assert low == sum(1 for f in ref.flags if f)
        assert page.locator("svg polyline.seg").count() == len(ref.time_s)
        route_page_fits(page, f"trajectory-{tag}", viewport)
    lines = downloaded_lines(page, "Waypoint times CSV")
    assert lines[0].endswith("time_s") and len(lines) == len(ref.waypoint_times_s) + 1


def cli_mission(plan: Path, *options: str) -> dict:
    """``uasnav trajectory mission PLAN --json``."""
    r = CliRunner().invoke(main, ["trajectory", "mission", str(plan), *options, "--json"])
    assert r.exit_code == 0, r.output
    return json.loads(r.output)


def test_autopilot_mission_on_desktop_and_phone(pages, server, shared_data) -> None:
    """The real QuadPlane plan: the page's ETA is the CLI's mission figure, the autopilot and
    QGroundControl's estimate are named; the stack chosen on the form gives the CLI's figure
    for that stack. Screenshots at 1366 and 390 px."""
    plan = shared_data / "missions" / "ardupilot_autotest_dalby_obc2016.waypoints"
    ref, as_copter = cli_mission(plan), cli_mission(plan, "--autopilot", "arducopter")
    for viewport, tag in ((DESKTOP, "desktop"), (PHONE, "phone")):
        page = predicted(pages.new(viewport), server, plan)
        assert float(page.get_attribute("#eta", "data-eta")) == ref["eta_s"]
        assert float(page.get_attribute("#qgc-eta", "data-eta")) == ref["qgc_estimate_s"]
        assert "ArduPlane" in page.locator("#autopilot").inner_text()
        assert page.locator("#mission-items td[data-arrive]").count() == len(ref["items"])
        route_page_fits(page, f"trajectory-mission-{tag}", viewport)
    rows = downloaded_lines(page, "Mission item times CSV")
    assert rows[0] == "item,command,name,arrive_s" and len(rows) == len(ref["items"]) + 1
    last = rows[-1].split(",")
    assert float(last[-1]) == pytest.approx(ref["items"][-1]["arrive_s"], abs=1e-3)
    page.select_option("#t-autopilot", "arducopter")
    page.set_input_files("#t-plan", str(plan))
    page.click("#trajectory-form button[type=submit]")
    landed(page, "prediction")
    assert float(page.get_attribute("#eta", "data-eta")) == as_copter["eta_s"]
    assert page.input_value("#t-autopilot") == "arducopter"


def test_database_pages_filter_and_sort(pages, server) -> None:
    page = pages.new()
    page.goto(server.url + "/db/uas")
    total = page.locator("#table tbody tr").count()
    page.fill("#q", "dji")
    visible = page.locator("#table tbody tr:not([hidden])")
    assert 0 < visible.count() < total
    assert all("dji" in t.lower() for t in visible.all_inner_texts())
    page.click("button:has-text('Filter')")  # the same filter on the server (works without JS)
    page.wait_for_url(re.compile(r"q=dji"))
    assert page.locator("#table tbody tr").count() == visible.count()
    shot(page, "database-desktop")
    page = pages.new(PHONE)
    page.goto(server.url + "/db/regulations")
    assert page.locator("#table tbody tr").count() > 0
    shot(page, "database-regulations-phone")


def test_not_authorisable_in_the_browser(pages, server, shared_data, tmp_path) -> None:
    """Zones and area uploaded through the form (file names kept): a PROHIBITED zone puts the
    verdict first and lists the configurations as withheld, as ``select --json`` does; the
    default-on GNSS-autopilot box, unchecked, is sent as false."""
    doc = json.loads((shared_data / "utm" / "interuss_ed269_geozone_sample.json").read_text())
    doc["UASZoneList"][0].update(restriction="PROHIBITED", message="military area")
    zones, area = tmp_path / "prohibited.json", tmp_path / "field.geojson"
    zones.write_text(json.dumps(doc))
    ring = [[6.1680, 46.2160], [6.1689, 46.2160], [6.1689, 46.2165], [6.1680, 46.2165], [6.1680, 46.2160]]
    area.write_text(json.dumps({"type": "Polygon", "coordinates": [ring]}))
    argv = [
        "select",
        "--json",
        "--range",
        "1500",
        "--zones",
        str(zones),
        "--area",
        str(area),
        "--no-gnss-autopilot",
    ]
    want = json.loads(
        subprocess.run([*uasnav_command(), *argv], capture_output=True, check=True, timeout=120).stdout
    )
    assert want["authorisation"]["authorisable"] is False
    for viewport, tag in ((DESKTOP, "desktop"), (PHONE, "phone")):
        page = pages.new(viewport)
        page.goto(server.url + "/")
        page.fill("#f-range", "1500")
        page.set_input_files("#f-zones", str(zones))
        page.set_input_files("#f-area", str(area))
        open_advanced(page)
        page.uncheck("#f-gnss_autopilot")
        page.click("#select-form button[type=submit]")
        landed(page)
        box = page.locator("#not-authorisable")
        assert box.is_visible() and want["authorisation"]["verdict"] in box.inner_text()
        assert page.locator("#ranking").count() == 0
        rows = page.locator("#withheld tbody tr")
        got = [
            (rows.nth(i).locator("td").nth(1).inner_text(), rows.nth(i).locator("td").nth(2).inner_text())
            for i in range(rows.count())
        ]
        assert got == [(w["uas"], w["camera"]) for w in want["withheld_ranking"]]
        assert page.locator(".auth-summary .verdict.warn").is_visible()
        n = len(want["rejections"])
        assert page.locator("#rejections tbody tr").count() == n
        shot(page, f"select-withheld-{tag}")
        assert page.evaluate("document.documentElement.scrollWidth") <= viewport["width"]


#: A 70 × 55 m field (lon, lat) beside Geneva.
FIELD_RING = [[6.1680, 46.2160], [6.1689, 46.2160], [6.1689, 46.2165], [6.1680, 46.2165], [6.1680, 46.2160]]


#: Downloads started per page visit (Chromium holds the eleventh in quick succession).
DOWNLOADS_PER_VISIT = 6


def run_by_keyboard(page) -> None:  # type: ignore[no-untyped-def]
    """Tab from the Range field to the run button and press Enter, as a keyboard user does."""
    page.focus("#f-range")
    for _ in range(30):
        if page.evaluate("document.activeElement.type") == "submit":
            break
        page.keyboard.press("Tab")
    with page.expect_navigation():
        page.keyboard.press("Enter")


def test_area_upload_map_results_downloads(pages, server, tmp_path) -> None:
    """Upload an area → the offline map → the results (focused) → every download, at desktop and
    phone widths; at phone width the ranking's priority columns (mass, cost, operation) are shown
    with a cue to scroll sideways, and the run button is on screen from the start."""
    area = tmp_path / "field.geojson"
    area.write_text(json.dumps({"type": "Polygon", "coordinates": [FIELD_RING]}))
    for viewport, tag in ((DESKTOP, "desktop"), (PHONE, "phone")):
        page = pages.new(viewport)
        page.goto(server.url + "/")
        box = page.locator("#select-form button[type=submit]").bounding_box()
        assert box and box["y"] + box["height"] <= viewport["height"], "run button below the fold"
        page.set_input_files("#f-area", str(area))
        page.fill("#f-range", "")  # with an area, distances come from the area
        if tag == "phone":  # keyboard only: Tab to the run button, Enter
            run_by_keyboard(page)
        else:
            page.click("#select-form button[type=submit]")
        landed(page)
        svg = page.locator("svg.map")
        assert svg.is_visible()
        assert page.locator("svg.map path.area").count() == 1
        assert page.locator("svg.map g.takeoff").count() == 1
        assert page.locator("svg.map polyline.survey").count() >= 1
        assert page.locator("#flights tbody tr").count() >= 1
        assert page.locator("svg.map g.north").count() == 1 and page.locator("svg.map g.scale").is_visible()
        head = page.locator("#ranking thead th")
        for name in ("Mass (g)", "Cost (USD)", "Operation"):
            assert head.filter(has_text=name).is_visible(), name
        if tag == "phone":
            assert page.locator("#ranking th.opt").first.is_hidden()
            wide = page.evaluate(
                "(() => { const b = document.querySelector('#ranking').closest('.scroll');"
                " return b.scrollWidth > b.clientWidth; })()"
            )
            cue = page.locator(".scroll-cue").first
            assert cue.is_visible() == wide
        shot(page, f"select-area-{tag}")
        assert page.evaluate("document.documentElement.scrollWidth") <= viewport["width"]
        names = []
        links = page.locator(".downloads a[download]")
        for i in range(links.count()):
            if i and i % DOWNLOADS_PER_VISIT == 0:
                # Chromium holds a page's eleventh download in quick succession behind its
                # "download multiple files" permission (headless: refused): the user runs the
                # page again (it keeps the uploaded area) and goes on from the same link
                if tag == "phone":
                    run_by_keyboard(page)
                else:
                    with page.expect_navigation():
                        page.click("#select-form button[type=submit]")
                landed(page)
            link = links.nth(i)
            with page.expect_download() as d:
                if tag == "phone":  # keyboard only
                    link.focus()
                    page.keyboard.press("Enter")
                else:
                    link.click()
            got = tmp_path / f"{tag}-{d.value.suggested_filename}"
            d.value.save_as(got)
            assert got.stat().st_size > 0
            names.append(d.value.suggested_filename)
        assert {"selection.json", "ranking.csv", "authorisation-summary.html"} <= set(names)
        # every file the plan writes, and the flight plan reads back
        want = {"flight-01.plan", "flight-01.waypoints", "flight-01.intent.json", "summary.html"}
        assert want | {"summary.json", "result.json"} <= set(names)
        route, _ = plan_route(read_plan(tmp_path / f"{tag}-flight-01.plan"))
        assert len(route) >= 2
        result = json.loads((tmp_path / f"{tag}-result.json").read_text())
        assert result["survey"]["lines"] == page.locator("svg.map polyline.survey").count()


def test_map_click_places_takeoff_and_pilot(pages, server, tmp_path) -> None:
    """A click on the offline map fills the take-off (then the pilot) field with the clicked
    latitude,longitude and moves its marker; the next run, on the area the page kept, plans
    from there and draws the points where they were clicked."""
    area = tmp_path / "field.geojson"
    area.write_text(json.dumps({"type": "Polygon", "coordinates": [FIELD_RING]}))
    page = pages.new()
    page.goto(server.url + "/")
    page.set_input_files("#f-area", str(area))
    page.fill("#f-range", "")
    page.click("#select-form button[type=submit]")
    landed(page)
    svg = page.locator("svg.map")
    box = svg.bounding_box()
    assert box and page.locator("#map-set").is_visible()
    placed = {}
    for which, (fx, fy) in (("takeoff", (0.3, 0.75)), ("pilot", (0.7, 0.3))):
        page.check(f"#map-set input[value={which}]")
        page.mouse.click(box["x"] + fx * box["width"], box["y"] + fy * box["height"])
        placed[which] = page.input_value(f"#f-{which}")
        lat, lon = map(float, placed[which].split(","))
        assert 46.2 < lat < 46.23 and 6.15 < lon < 6.18, placed[which]
        assert placed[which] in page.locator("#map-status").inner_text()
        dot = page.locator(f"svg.map g.pt.{which} circle").bounding_box()
        assert dot and abs(dot["x"] + dot["width"] / 2 - (box["x"] + fx * box["width"])) < 2
    assert placed["takeoff"] != placed["pilot"]
    shot(page, "select-map-placed-desktop")
    page.click("#select-form button[type=submit]")  # no new upload: the kept area
    landed(page)
    assert page.locator("#plan").count() == 1
    for which, text in placed.items():
        assert page.input_value(f"#f-{which}") == text
        lat, lon = map(float, text.split(","))
        got = page.evaluate(
            """(which) => {
              const svg = document.querySelector("svg.map"), c = svg.querySelector(`g.pt.${which} circle`);
              const n = (s) => s.split(",").map(Number);
              const [lat0, lon0] = n(svg.dataset.origin), [mLat, mLon] = n(svg.dataset.mPerDeg);
              const [ox, oy, k, x0, y1] = n(svg.dataset.view);
              const e = x0 + (c.cx.baseVal.value - ox) / k, no = y1 - (c.cy.baseVal.value - oy) / k;
              return [lat0 + no / mLat, lon0 + e / mLon];
            }""",
            which,
        )
        assert abs(got[0] - lat) * 111e3 < 0.5 and abs(got[1] - lon) * 77e3 < 0.5, (which, got, text)


def test_map_taps_place_takeoff_and_pilot_on_a_phone(pages, server, tmp_path) -> None:
    """On a 390 px touch screen, taps (touch events, no mouse) on the offline map set the
    take-off point and then the pilot's position; the next run plans from them, and the
    regulation line gives the pilot distance in whole metres."""
    area = tmp_path / "field.geojson"
    area.write_text(json.dumps({"type": "Polygon", "coordinates": [FIELD_RING]}))
    page = pages.new(PHONE, has_touch=True, is_mobile=True)
    assert page.evaluate("navigator.maxTouchPoints") > 0
    page.goto(server.url + "/")
    page.set_input_files("#f-area", str(area))
    page.fill("#f-range", "")
    page.tap("#select-form button[type=submit]")
    landed(page)
    svg = page.locator("svg.map")
    svg.scroll_into_view_if_needed()
    size = svg.bounding_box()
    assert size and size["width"] <= PHONE["width"] and page.locator("#map-set").is_visible()
    placed = {}
    for which, (fx, fy) in (("takeoff", (0.35, 0.7)), ("pilot", (0.65, 0.35))):
        page.locator(f"#map-set input[value={which}]").tap()
        assert page.is_checked(f"#map-set input[value={which}]")
        svg.tap(position={"x": fx * size["width"], "y": fy * size["height"]})
        placed[which] = page.input_value(f"#f-{which}")
        lat, lon = map(float, placed[which].split(","))
        assert 46.2 < lat < 46.23 and 6.15 < lon < 6.18, placed[which]
        assert placed[which] in page.locator("#map-status").inner_text()
        box = svg.bounding_box()
        dot = page.locator(f"svg.map g.pt.{which} circle").bounding_box()
        assert box and dot
        assert abs(dot["x"] + dot["width"] / 2 - (box["x"] + fx * box["width"])) < 2
        assert abs(dot["y"] + dot["height"] / 2 - (box["y"] + fy * box["height"])) < 2
    assert placed["takeoff"] != placed["pilot"]
    shot(page, "select-map-tapped-phone")
    page.tap("#select-form button[type=submit]")  # the kept area, from the tapped points
    landed(page)
    assert page.locator("#plan").count() == 1
    for which, text in placed.items():
        assert page.input_value(f"#f-{which}") == text
    notes = " ".join(page.locator("p.note").all_inner_texts())
    shown = re.findall(r"(\d[\d.,]*) m from the pilot", notes)
    assert shown and all(re.fullmatch(r"\d+", x) for x in shown), notes
    shot(page, "select-map-tapped-result-phone")
    assert page.evaluate("document.documentElement.scrollWidth") <= PHONE["width"]


def test_oversize_upload_is_refused_beside_the_field(pages, server, tmp_path) -> None:
    big = tmp_path / "big.geojson"
    with big.open("wb") as f:
        f.truncate(17 * 2**20)
    page = pages.new(PHONE)
    page.goto(server.url + "/")
    page.fill("#f-wind", "7")
    page.set_input_files("#f-area", str(big))
    assert "over the 16 MB limit" in page.locator("#e-area").inner_text()
    page.click("#select-form button[type=submit]")
    assert page.locator("#results").count() == 0 and page.input_value("#f-wind") == "7"
    assert page.evaluate("document.activeElement.id") == "f-area"


def test_trajectory_prints_on_one_a4_page(pages, server, tmp_path) -> None:
    import pymap3d

    from uasnav.trajectory.simulator import phantom4_plans

    ne = phantom4_plans()["B"]
    lat, lon, _ = pymap3d.ned2geodetic(ne[:, 0], ne[:, 1], 0.0, 47.3977, 8.5456, 50.0)
    csv = tmp_path / "b.csv"
    csv.write_text("lat,lon,alt\n" + "".join(f"{a:.9f},{b:.9f},50\n" for a, b in zip(lat, lon, strict=True)))
    page = pages.new()
    page.goto(server.url + "/trajectory")
    page.set_input_files("#t-plan", str(csv))
    page.fill("#t-required", ",".join(str(10 * i) for i in range(len(ne))))
    page.click("#trajectory-form button[type=submit]")
    landed(page, "prediction")
    times = page.locator("#waypoints td[data-time]").all_inner_texts()
    assert_route_labels_inside(page)
    page.emulate_media(media="print")
    assert not page.locator("#trajectory-form").is_visible()
    pdf = pypdf.PdfReader(io.BytesIO(page.pdf(format="A4", print_background=True)))
    assert len(pdf.pages) == 1
    printed = pdf.pages[0].extract_text()
    assert "ETA" in printed and all(t in printed for t in times)  # every waypoint time, none cut
