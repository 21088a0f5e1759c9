"""The front page (floorscan.figures.report) from small inputs, and workflow.rst including it the
way Snakemake's report renders its workflow description."""

import json
import math
import re
from html.parser import HTMLParser
from pathlib import Path

import matplotlib

matplotlib.use("Agg")
import matplotlib.pyplot as plt  # noqa: E402
import pandas as pd  # noqa: E402
import pytest  # noqa: E402

from floorscan.figures import report as R  # noqa: E402
from floorscan.figures.pages import OutputFile  # noqa: E402
from floorscan.core.score_tables import SUMMARY_COLUMNS  # noqa: E402

REPO = Path(__file__).resolve().parents[1]

SVG = (
    '<?xml version="1.0" encoding="UTF-8"?>\n'
    '<svg xmlns="http://www.w3.org/2000/svg" width="333" height="305" viewBox="-0.8 -7.0 8.3 7.6">\n'
    "<title>toy plan</title>\n"
    '<g transform="scale(1,-1)"><g id="walls" fill="#9a9a9a">'
    '<polygon points="0,0 6,0 6,0.1 0,0.1"/></g>'
    '<g id="axes" stroke="#c00"><line x1="0" y1="0.05" x2="6" y2="0.05"><title>wall 0</title></line></g></g>\n'
    "</svg>\n"
)
VERDICT = {
    "ok": True, "line": "GOOD: kept 76 of 76 sampled scans (100 %); map consistency 0.88 (1764 revisited points)",
    "n_sampled": 76, "n_kept": 76, "kept_fraction": 1.0, "consistency": 0.88, "n_revisited": 1764,
    "problems": [], "warnings": [],
}  # fmt: skip
DETECTED = {"format": "rosbag", "scan_topic": "/scan", "pose_source": "topic /amcl_pose", "stamps": "recorded",
            "pose_kind": "map", "dataset": "toy"}


def _summary() -> pd.DataFrame:
    nan = math.nan
    rows = [
        ("cluster_ransac", "oracle", 1, 4, nan, 0.867, nan, 1.0),
        ("cluster_ransac", "random", 10, 10, 4, 0.782, 0.028, 2.48),
        ("cluster_ransac", "wall_coverage", 1, 4, nan, 0.853, nan, 1.0),
    ]
    out = []
    for extractor, ordering, n_seeds, k95, k95_sd, auc, auc_sd, over in rows:
        out.append({
            "dataset": "toy", "extractor": extractor, "ordering": ordering, "n_seeds": n_seeds, "f1_all": 0.932,
            "k_95": float(k95), "fraction_kept_95": k95 / 76, "fraction_recorded_95": k95 / 321,
            "k_95_seed_sd": float(k95_sd), "k_99": float(k95 + 1), "fraction_kept_99": (k95 + 1) / 76,
            "fraction_recorded_99": (k95 + 1) / 321, "k_99_seed_sd": nan, "auc": auc, "auc_seed_sd": auc_sd,
            "k95_over_oracle": over,
        })  # fmt: skip
    return pd.DataFrame(out)


class _Tables(HTMLParser):
    """Rows of the page's tables as lists of cell texts, and the class of each row."""

    def __init__(self):
        super().__init__()
        self.rows, self.row_classes, self._cell = [], [], None

    def handle_starttag(self, tag, attrs):
        if tag == "tr":
            self.rows.append([])
            self.row_classes.append(dict(attrs).get("class", ""))
        elif tag in ("td", "th"):
            self._cell = []

    def handle_endtag(self, tag):
        if tag in ("td", "th") and self._cell is not None:
            self.rows[-1].append("".join(self._cell).strip())
            self._cell = None

    def handle_data(self, data):
        if self._cell is not None:
            self._cell.append(data)


def _tiny_png(path: Path) -> Path:
    fig, ax = plt.subplots(figsize=(1, 1))
    ax.plot([0, 1], [0, 1])
    fig.savefig(path)
    plt.close(fig)
    return path


def _page(tmp_path, **kw):
    args = dict(
        floorplan_svg=SVG, summary=_summary(), verdict=VERDICT, detected=DETECTED, mode="pose",
        quality_png=_tiny_png(tmp_path / "quality_vs_k.png"),
        scan_list=OutputFile("scan list", "selection/scans.csv", True),
        k=4, n_kept=76, n_recorded=321, bytes_in=3_456_789, bytes_out=61_234,
        k_reason="k = 4: the first k scans reach 99 % of the coverage of all 76.",
        ordering="wall_coverage", extractor="cluster_ransac", n_walls=16, description="A toy building",
    )  # fmt: skip
    args.update(kw)
    return R.front_page(R.FrontPage("toy", **args))


def test_front_page_holds_the_plan_the_verdict_the_detection_and_the_table(tmp_path):
    page = _page(tmp_path)
    # the floor plan inline, scaled by its viewBox, without its XML declaration
    assert "<?xml" not in page
    svg = re.search(r"<svg\b[^>]*>", page).group(0)
    assert 'viewBox="-0.8 -7.0 8.3 7.6"' in svg and "width=" not in svg and "height=" not in svg
    assert '<line x1="0" y1="0.05" x2="6" y2="0.05">' in page
    assert "The recommended floor plan, 16 walls, from the first 4 scans of the wall_coverage ordering" in page
    # the verdict, coloured by its first word
    assert '<p class="verdict good">Registration: GOOD: kept 76 of 76 sampled scans (100 %)' in page
    # the quality figure as a data URI: the page stands alone
    assert 'src="data:image/png;base64,iVBORw0KGgo' in page
    tables = _Tables()
    tables.feed(page)
    rows = {r[0]: r[1:] for r in tables.rows if len(r) == 2}
    assert rows["scans used"] == ["4 of 76 kept, 321 recorded (1.2 %)"]
    assert rows["recording"] == ["3.46 MB → 61.2 kB (1.8 %)"]
    assert rows["scan list"] == ["selection/scans.csv"]  # relative to the page, a link
    assert '<a href="selection/scans.csv"><code>selection/scans.csv</code></a>' in page
    assert rows["format"] == ["rosbag"] and rows["scan topic"] == ["/scan"]
    assert rows["pose source"] == ["topic /amcl_pose"] and rows["registered in"] == ["pose mode"]
    # the summary: one row per ordering, the cells as summary.md has them (± for random's seeds)
    summary_rows = [(r, c) for r, c in zip(tables.rows, tables.row_classes) if len(r) == len(SUMMARY_COLUMNS)]
    assert [r[0] for r, _ in summary_rows[:1]] == ["extractor"]  # the header
    body = {r[1]: (r, c) for r, c in summary_rows[1:]}
    assert sorted(body) == ["oracle", "random", "wall_coverage"]
    assert body["random"][0] == ["cluster_ransac", "random", "0.932", "10 ± 4", "0.132", "0.031", "11", "0.145",
                                 "0.034", "0.782 ± 0.028", "2.48"]
    assert body["wall_coverage"][0][3] == "4" and body["wall_coverage"][1] == "recommended"
    assert body["oracle"][1] == "bound"
    # beside the plan, before the full table: the scans the recommended ordering needs
    # against random and the oracle (no cluster_hull row in this summary)
    quality = [(r, c) for r, c in zip(tables.rows, tables.row_classes) if len(r) == len(R.QUALITY_COLUMNS)]
    assert quality[0][0] == ["ordering", "k95", "k99", "AUC 20 %"]
    assert [r[0] for r, _ in quality[1:]] == ["wall_coverage", "oracle", "random"]
    assert quality[1][0][1] == "4" and quality[1][1] == "recommended" and quality[2][1] == "bound"
    assert quality[3][0][1] == "10 ± 4"
    assert page.index("Scans needed (cluster_ransac walls)") < page.index("What ingest detected")
    assert "wall_coverage beats random with cluster_ransac" in page
    assert "k = 4: the first k scans reach 99 %" in page


def test_front_page_can_sit_in_the_reports_script_string(tmp_path):
    # Snakemake puts the workflow description, which includes the page, in a <script>
    page = _page(tmp_path, description="</script><script>alert(1)</script>", verdict="POOR: <b>bad</b>")
    assert "<script" not in page.lower() and "</script" not in page.lower() and "<!--" not in page
    assert '<p class="verdict poor">Registration: POOR: &lt;b&gt;bad&lt;/b&gt;</p>' in page
    with pytest.raises(ValueError, match="script"):
        R.inline_svg(SVG.replace("<title>toy plan</title>", "<script>x()</script>"))
    with pytest.raises(ValueError, match="no <svg>"):
        R.inline_svg("<html></html>")


def test_front_page_without_evaluation_or_selection(tmp_path):
    page = R.front_page(R.FrontPage("toy", floorplan_svg=SVG, verdict=None, detected={}))
    assert "Not evaluated in this run" in page
    assert "Registration: no verdict recorded." in page
    assert "<h3>Scans</h3>" not in page and "data:image/png" not in page
    assert "registered in</th><td>pose mode" in page


def test_write_front_page_writes_the_page_and_no_temporary_file(tmp_path):
    out = tmp_path / "toy" / "front.html"
    text = R.write_front_page(out, R.FrontPage("toy", floorplan_svg=SVG, summary=_summary(), verdict=VERDICT))
    assert out.read_text(encoding="utf-8") == text
    assert [p.name for p in out.parent.iterdir()] == ["front.html"]


def test_front_page_of_the_stage_outputs(tmp_path):
    from floorscan.floorplan.plan import build_floorplan
    from floorscan.floorplan.scans import write_plan
    from floorscan.floorplan.svg import write_svg
    from floorscan.core.io import SCAN_INDEX, write_table

    segments = pd.DataFrame(
        [(0, 0, 6, 0), (6, 0.2, 0, 0.2), (6, 0, 6, 4), (0, 4, 0, 0)], columns=["x0", "y0", "x1", "y1"]
    ).assign(n_inliers=100)
    plan = build_floorplan(segments)
    write_svg(plan, tmp_path / "floorplan.svg")
    write_plan(plan, tmp_path / "plan_tables")
    selection = {
        "dataset": "toy", "ordering": "wall_coverage", "k": 3, "reason": "k = 3 by the rule", "n_kept": 30,
        "n_recorded": 40, "scans": "results/toy/selection/scans.csv",
        "recording": {"bytes_in": 2_000_000, "bytes_out": 150_000, "path": "results/toy/selection/recording/x.bag"},
    }  # fmt: skip
    (tmp_path / "selection.json").write_text(json.dumps(selection))
    index = pd.DataFrame({"scan_id": range(40), "t_ns": range(40), "n_points": 10, "n_dropped": 0, "frame": "laser"})
    write_table(index, tmp_path / "scan_index.parquet", SCAN_INDEX, metadata=DETECTED)
    write_table(pd.DataFrame({"scan_id": [0, 1]}), tmp_path / "registration.parquet",
                metadata={"verdict": json.dumps(VERDICT), "mode": "odometry"})
    summary = _summary()
    write_table(summary, tmp_path / "summary.parquet")
    out = tmp_path / "front.html"
    page = R.write_front_page_of_files(
        out, "toy", floorplan_svg=tmp_path / "floorplan.svg", plan=tmp_path / "plan_tables",
        selection=tmp_path / "selection.json", registration=tmp_path / "registration.parquet",
        index=tmp_path / "scan_index.parquet", summary=tmp_path / "summary.parquet",
        quality_png=_tiny_png(tmp_path / "q.png"), extractor="cluster_ransac",
    )  # fmt: skip
    assert out.read_text(encoding="utf-8") == page
    assert f"The recommended floor plan, {len(plan.walls)} walls, from the first 3 scans" in page
    assert "toy: floor plan from 3 of 40 recorded scans" in page
    assert "2 MB → 150 kB (7.5 %)" in page and "k = 3 by the rule" in page
    assert "odometry mode" in page and "GOOD: kept 76" in page
    # summary and header; scans; the quality table (header, wall_coverage, oracle, random); 4 detected, the mode
    assert page.count("<tr") == len(summary) + 1 + 3 + 4 + 5


@pytest.mark.filterwarnings("ignore:Argument \"writer_name\":PendingDeprecationWarning")  # as Snakemake calls it
def test_workflow_description_includes_each_front_page(tmp_path, monkeypatch):
    """workflow.rst rendered as Snakemake 9.27 renders the report's workflow description
    (snakemake/report/__init__.py, auto_report: jinja with ``snakemake.config``,
    ``categories``, ``files``, then docutils to HTML) includes each dataset's front page,
    before the text on the workflow, with no docutils error."""
    from docutils.core import publish_parts
    from jinja2 import Environment
    from snakemake.report import Category

    monkeypatch.chdir(tmp_path)  # the report is made in the workflow's directory
    fronts = {}
    for ds in ("beta", "alpha"):
        path = Path("results") / ds / "front.html"
        R.write_front_page(path, R.FrontPage(ds, floorplan_svg=SVG, summary=_summary(), verdict=VERDICT))
        fronts[ds] = type("Record", (), {"name": path.name, "path": path})()
    figure = type("Record", (), {"name": "quality_vs_k.png", "path": Path("results/alpha/q.png")})()
    categories = {
        Category("Scoring"): {Category("alpha"): [figure]},
        Category("Floor plan"): {Category(ds): [rec] for ds, rec in fronts.items()},
    }

    class Snakemake:
        config = {"target": ["beta", "alpha"]}

    text = (REPO / "workflow" / "report" / "workflow.rst").read_text()
    rst = Environment(trim_blocks=True, lstrip_blocks=True).from_string(text).render(
        snakemake=Snakemake, categories=categories, files=[figure, *fronts.values()]
    )
    body = publish_parts(rst, writer_name="html")["html_body"]
    assert "System Message" not in body and "system-message" not in body
    alpha, beta = body.index('id="front-alpha"'), body.index('id="front-beta"')
    assert alpha < beta < body.index("How the workflow works")
    assert body.count("<svg") == 2 and "No front page in this report" not in body
    assert "#app .prose.max-w-lg" in body  # the report's layout opened up for the pages
    # the datasets of its front pages, not the run's targets (a failed one has none)
    assert "Datasets in this report: alpha, beta." in body


# ------------------------------------------------------------------ links, k, escaping


class _Links(HTMLParser):
    """The page's links (href) and the text of each ``<code class="missing">``."""

    def __init__(self):
        super().__init__()
        self.hrefs, self.missing, self._in_missing = [], [], False

    def handle_starttag(self, tag, attrs):
        a = dict(attrs)
        if tag == "a":
            self.hrefs.append(a["href"])
        elif tag == "code" and a.get("class") == "missing":
            self._in_missing = True
            self.missing.append("")

    def handle_endtag(self, tag):
        if tag == "code":
            self._in_missing = False

    def handle_data(self, data):
        if self._in_missing:
            self.missing[-1] += data


def _links(page: str) -> _Links:
    links = _Links()
    links.feed(page)
    return links


def _answer_folder(root: Path, ds: str = "toy", skip=()) -> tuple[Path, dict]:
    """results/<ds>/ with every file a front page links, but those in ``skip``; the
    selection as selection.json names them (relative to ``root``, the working directory)."""
    folder = root / "results" / ds
    names = ["floorplan.svg", "floorplan.geojson", "floorplan.dxf", "floorplan.ifc", "map.pgm", "map.yaml",
             "selection/scans.csv", "selection/recording/recording.bag", "selection/points.ply",
             "selection/points.pcd", "summary.md"]  # fmt: skip
    for name in names:
        if name not in skip:
            (folder / name).parent.mkdir(parents=True, exist_ok=True)
            (folder / name).write_text("x")
    sel = {"scans": f"results/{ds}/selection/scans.csv", "points": [f"results/{ds}/selection/points.ply",
           f"results/{ds}/selection/points.pcd"], "recording": {"path": f"results/{ds}/selection/recording/recording.bag"}}  # fmt: skip
    return folder, sel


def test_every_file_the_page_names_is_a_link_that_resolves(tmp_path, monkeypatch):
    monkeypatch.chdir(tmp_path)  # the selection's paths are relative to the working directory
    folder, sel = _answer_folder(tmp_path)
    (tmp_path / "results" / "index.html").write_text("index")
    files = R.answer_files(folder, sel)
    assert [f.href for f in files] == [
        "floorplan.svg", "floorplan.geojson", "floorplan.dxf", "floorplan.ifc", "map.pgm", "map.yaml",
        "selection/scans.csv", "selection/recording/recording.bag", "selection/points.ply", "selection/points.pcd",
        "summary.md",
    ]  # fmt: skip
    page = R.front_page(R.FrontPage("toy", floorplan_svg=SVG, files=files, report=R.report_file(folder),
                                    scan_list=files[6]))  # fmt: skip
    links = _links(page)
    assert links.missing == ["../report.html"]  # no report made: named, not linked, and said so
    assert "<code class=\"missing\">../report.html</code> (not made yet: <code>floorscan report</code>" in page
    assert "../index.html" in links.hrefs  # back to the index
    for f in files:
        assert f.href in links.hrefs, f.href
    for href in links.hrefs:  # every link resolves from the page's folder
        assert (folder / href).is_file(), href
    assert links.hrefs.count("selection/scans.csv") == 2  # in the files and in the scans' table
    # a report made since: linked too
    (tmp_path / "results" / "report.html").write_text("report")
    assert "../report.html" in _links(R.front_page(R.FrontPage("toy", floorplan_svg=SVG, report=R.report_file(folder)))).hrefs


def test_a_missing_file_is_named_and_not_linked(tmp_path, monkeypatch):
    monkeypatch.chdir(tmp_path)
    folder, sel = _answer_folder(tmp_path, skip=("floorplan.ifc", "selection/points.pcd"))
    page = R.front_page(R.FrontPage("toy", floorplan_svg=SVG, files=R.answer_files(folder, sel)))
    links = _links(page)
    assert sorted(links.missing) == ["floorplan.ifc", "selection/points.pcd"]
    assert "floorplan.ifc" not in links.hrefs and "selection/points.pcd" not in links.hrefs
    assert "floorplan.dxf" in links.hrefs
    assert 'was not there when this page was written: it is named, not linked' in page


def test_the_page_of_the_stage_outputs_links_what_exists(tmp_path, monkeypatch):
    """write_front_page_of_files: links relative to results/<dataset>/, from the
    selection's paths (relative to the working directory)."""
    from floorscan.core.io import SCAN_INDEX, write_table
    from floorscan.floorplan.plan import build_floorplan
    from floorscan.floorplan.scans import write_plan
    from floorscan.floorplan.svg import write_svg

    monkeypatch.chdir(tmp_path)
    folder, sel = _answer_folder(tmp_path, skip=("map.yaml",))
    segments = pd.DataFrame([(0, 0, 6, 0), (6, 0.2, 0, 0.2), (6, 0, 6, 4), (0, 4, 0, 0)],
                            columns=["x0", "y0", "x1", "y1"]).assign(n_inliers=100)  # fmt: skip
    plan = build_floorplan(segments)
    write_svg(plan, folder / "floorplan.svg")
    write_plan(plan, folder / "plan_tables")
    sel.update({"dataset": "toy", "ordering": "wall_coverage", "k": 3, "reason": "k = 3 by the rule", "n_kept": 30,
                "n_recorded": 40})  # fmt: skip
    sel["recording"].update(bytes_in=2_000_000, bytes_out=150_000)
    (folder / "selection" / "selection.json").write_text(json.dumps(sel))
    index = pd.DataFrame({"scan_id": range(40), "t_ns": range(40), "n_points": 10, "n_dropped": 0, "frame": "laser"})
    write_table(index, folder / "scan_index.parquet", SCAN_INDEX, metadata=DETECTED)
    write_table(pd.DataFrame({"scan_id": [0, 1]}), folder / "registration.parquet",
                metadata={"verdict": json.dumps(VERDICT), "mode": "pose"})  # fmt: skip
    page = R.write_front_page_of_files(
        "results/toy/front.html", "toy", floorplan_svg="results/toy/floorplan.svg", plan="results/toy/plan_tables",
        selection="results/toy/selection/selection.json", registration="results/toy/registration.parquet",
        index="results/toy/scan_index.parquet",
    )  # fmt: skip
    links = _links(page)
    assert sorted(links.missing) == ["../report.html", "map.yaml"]
    for href in links.hrefs:
        assert href == "../index.html" or (folder / href).is_file(), href
    for name in ("floorplan.ifc", "floorplan.dxf", "map.pgm", "selection/scans.csv", "summary.md",
                 "selection/recording/recording.bag", "selection/points.ply", "selection/points.pcd"):  # fmt: skip
        assert name in links.hrefs, name


def test_the_template_escapes_what_it_is_given(tmp_path):
    """Autoescape: a dataset name, a description, a file's name and a verdict are text."""
    page = R.front_page(R.FrontPage(
        "a<b&c", floorplan_svg=SVG, description="<i>x</i>", verdict="GOOD: <b>ok</b>",
        files=[OutputFile('odd"<name>', 'x"<y>.ifc', True)],
    ))  # fmt: skip
    assert "<title>a&lt;b&amp;c: floor plan</title>" in page and "<h2>a&lt;b&amp;c: floor plan</h2>" in page
    assert 'id="front-a&lt;b&amp;c"' in page
    assert "<p>&lt;i&gt;x&lt;/i&gt;</p>" in page and "GOOD: &lt;b&gt;ok&lt;/b&gt;" in page
    assert 'href="x&#34;&lt;y&gt;.ifc"' in page and "odd&#34;&lt;name&gt;:" in page
    assert "<i>" not in page and "<b>" not in page and "a<b" not in page
    assert '<line x1="0" y1="0.05"' in page  # the plan's SVG alone passes as markup


def test_the_page_says_why_k_differs_from_k95_and_k99_beside_them(tmp_path):
    curve = pd.DataFrame({"k": [1, 2, 3, 4, 5, 76], "f1_5cm": [0.5, 0.8, 0.90, 0.91, 0.93, 0.93]})
    answer = pd.DataFrame([{"plan": "recommended", "n_walls": 5}, {"plan": "all_scans_map", "n_walls": 6}])
    reason = "k = 10 of 76 kept scans: the smallest k whose wall_coverage reaches 99 % of what all scans cover"
    page = _page(tmp_path, k=10, k_reason=reason, answer=answer, answer_curve=curve)
    why = re.search(r'<p class="note why-k">([^<]*)</p>', page).group(1)
    assert why.startswith("k = 10 is more than the k95 = 3 and k99 = 5 of this plan&#39;s curve because")
    assert reason in why and "the extra scans are a margin" in why
    # beside the figures: after both tables with k95 / k99, before the rooms and what ingest detected
    assert page.index("(k99)</th>") < page.index("Scans needed") < page.index('class="note why-k"') < page.index("What ingest detected")
    assert page.count(reason) == 1  # said once, as the explanation
    # fewer than k95 (trace0: k = 53, k99 = 221), from the summary when no answer curve
    fewer = _page(tmp_path, k=2, k_reason="k = 2 by the rule")
    assert "k = 2 is fewer than the k95 = 4 and k99 = 5 of the wall_coverage curve because" in fewer
    assert "below 95 %" in fewer
    # k equal to one of them: nothing to explain; the reason stays under the scans
    same = _page(tmp_path, k=4, k_reason="k = 4 by the rule")
    assert 'class="note why-k"' not in same and '<p class="note">k = 4 by the rule</p>' in same


def test_the_map_page_links_its_files_and_the_index(tmp_path, monkeypatch):
    from floorscan.figures.map_page import MapFrontPage, map_front_page

    monkeypatch.chdir(tmp_path)
    folder, _ = _answer_folder(tmp_path, "two<rooms", skip=("floorplan.dxf",))
    info = {"image": "m.pgm", "path": "m.yaml", "width": 10, "height": 5, "resolution_m": 0.05, "origin_x_m": 0,
            "origin_y_m": 0, "mode": "trinary", "negate": 0, "occupied_thresh": 0.65, "free_thresh": 0.196,
            "n_occupied": 1, "n_free": 2, "n_unknown": 3}  # fmt: skip
    page = map_front_page(MapFrontPage("two<rooms", floorplan_svg=SVG, info=info, files=R.answer_files(folder)))
    links = _links(page)
    assert links.missing == ["floorplan.dxf"] and "../index.html" in links.hrefs
    assert [h for h in links.hrefs if h != "../index.html"] == [
        "floorplan.svg", "floorplan.geojson", "floorplan.ifc", "map.pgm", "map.yaml", "summary.md"]
    assert all((folder / h).is_file() for h in links.hrefs if h != "../index.html")
    assert "<h2>two&lt;rooms: floor plan of an occupancy map</h2>" in page and "What was read" in page
    assert "<script" not in page and "<!--" not in page


def test_summary_page_is_the_template_with_the_front_pages_table(tmp_path):
    """summary.html (floorscan.figures.summary_page): in the front page's frame (its
    style, the link back to the index, the report named until it is made), the verdict
    coloured by its class and the beats-random line escaped, and the summary table of
    the front page's macro with its note: its header, a row per ordering, the
    recommended ordering's row highlighted, the oracle's grey."""
    from floorscan.figures.summary_page import write_summary_page

    page = tmp_path / "toy" / "summary.html"
    page.parent.mkdir()
    write_summary_page(page, "toy <1>", _summary(), 76, "wall_coverage beats random & more", VERDICT, "wall_coverage")
    text = page.read_text(encoding="utf-8")
    assert text.startswith("<!DOCTYPE html>") and "<title>toy &lt;1&gt;: how few scans the floor plan needs</title>" in text
    assert ".floorscan-front { font-family" in text and '<div class="floorscan-front" id="front-toy &lt;1&gt;">' in text
    links = _links(text)
    assert links.hrefs == ["../index.html"] and links.missing == ["../report.html"]
    assert f'<p class="verdict good">Registration: {VERDICT["line"]}</p>' in text
    assert "<p>wall_coverage beats random &amp; more</p>" in text and "<script" not in text
    (tmp_path / "report.html").write_text("report")
    write_summary_page(page, "toy", _summary(), 76, "", {"line": "POOR: kept 3 of 76"}, "wall_coverage")
    text = page.read_text(encoding="utf-8")
    assert _links(text).hrefs == ["../index.html", "../report.html"]
    assert '<p class="verdict poor">Registration: POOR: kept 3 of 76</p>' in text and "beats random" not in text
    tables = _Tables()
    tables.feed(text)
    assert tables.rows[0] == [h for _, h in SUMMARY_COLUMNS]
    body = {r[1]: (r, c) for r, c in zip(tables.rows[1:], tables.row_classes[1:])}
    assert sorted(body) == ["oracle", "random", "wall_coverage"]
    assert body["wall_coverage"][1] == "recommended" and body["oracle"][1] == "bound" and body["random"][1] == ""
    assert body["random"][0][3] == "10 ± 4" and body["oracle"][0][3] == "4"
    # the front page shows the same table, from the same macro
    front = R.front_page(R.FrontPage(dataset="toy", floorplan_svg=SVG, summary=_summary(), verdict=VERDICT,
                                     k=4, n_kept=76, n_recorded=321, ordering="wall_coverage"))
    start = front.index("<table>\n<thead><tr><th>extractor</th>")
    assert front[start:front.index("</table>", start)] in text
    note = front.index('<p class="note">Every floor plan is scored', start)
    assert front[note:front.index("</p>", note)] in text
