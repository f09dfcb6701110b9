"""report.html in a real headless Chromium (Debian's package; `make system-deps` installs it).

A real run of the headless command on a small generated collection writes the page; Chromium
then opens it from disk (no server, networking switched off) and must load every image, and
its screenshot must show the style map's cluster colours and the orange style regions.
"""
import json
import re
import shutil
import subprocess
import sys
from pathlib import Path

import numpy as np
import pytest
from PIL import Image

ROOT = Path(__file__).resolve().parent.parent
pytestmark = [pytest.mark.blender, pytest.mark.slow]

CHROMIUM_FLAGS = ["--headless", "--no-sandbox", "--disable-gpu", "--disable-quic", "--no-first-run",
                  "--disable-background-networking", "--disable-component-update", "--disable-sync"]

# appended to a copy of the page: records, once everything has loaded, what each image became
PROBE = """<script>
window.addEventListener('load', () => {
  const rows = Array.from(document.images).map(i => [i.getAttribute('src'), i.complete, i.naturalWidth]);
  const pre = document.createElement('pre'); pre.id = 'probe';
  pre.textContent = JSON.stringify(rows); document.body.appendChild(pre);
});
</script>"""


def chromium() -> str:
    exe = shutil.which("chromium") or shutil.which("chromium-browser")
    if exe is None:
        pytest.fail("Chromium is missing: `make system-deps` installs Debian's chromium package")
    return exe


def run_chromium(tmp: Path, *args) -> subprocess.CompletedProcess:
    profile = tmp / "profile"
    shutil.rmtree(profile, ignore_errors=True)     # a fresh profile every time
    return subprocess.run([chromium(), *CHROMIUM_FLAGS, f"--user-data-dir={profile}", *args],
                          capture_output=True, text=True, timeout=180)


@pytest.fixture(scope="module")
def report_dir(tmp_path_factory):
    tmp = tmp_path_factory.mktemp("report")
    sample = tmp / "sample"
    py = [sys.executable, "-m", "style_coanalysis"]
    res = subprocess.run(py + ["sample", "--out", sample, "--size", "8", "--seed", "3"], cwd=ROOT,
                         capture_output=True, text=True, timeout=300)
    assert res.returncode == 0, res.stderr[-2000:]
    rows = [l.split(",") for l in (sample / "labels.csv").read_text().splitlines()[1:]]
    first = {}
    for name, style, *_ in rows:                    # one given label per style
        first.setdefault(style, name)
    (tmp / "labels.csv").write_text("name,style\n" + "".join(f"{n},{s}\n" for s, n in first.items()))
    out = tmp / "result"
    res = subprocess.run(py + ["analyze", sample / "sample.blend", "--out", out, "--renderer", "lineart",
                               "--jobs", "1", "--cache", tmp / "cache", "--rounds", "2",
                               "--labels", tmp / "labels.csv"],
                         cwd=ROOT, capture_output=True, text=True, timeout=900)
    assert res.returncode == 0, res.stderr[-3000:]
    return out


def test_every_image_of_the_page_loads_in_chromium(report_dir, tmp_path):
    page = (report_dir / "report.html").read_text()
    probe = report_dir / "probe.html"              # beside the page: the same relative image paths
    probe.write_text(page.replace("</html>", PROBE + "</html>"))
    res = run_chromium(tmp_path, "--virtual-time-budget=20000", "--dump-dom", probe.as_uri())
    probe.unlink()
    found = re.search(r"<pre id=\"probe\">(.*?)</pre>", res.stdout, re.S)
    assert found, f"the page did not finish loading: {res.stderr[-2000:]}"
    images = json.loads(found.group(1).replace("&quot;", '"').replace("&amp;", "&"))
    srcs = [s for s, _, _ in images]
    broken = [s for s, complete, width in images if not complete or width == 0]
    assert not broken, f"images that did not load: {broken}"
    rep = json.loads((report_dir / "report.json").read_text())
    assert "images/style_map.png" in srcs
    for s in rep["shapes"]:                        # every shape's best view and its style regions
        assert f"images/{s['name']}_lines.png" in srcs and f"images/{s['name']}_shaded.png" in srcs
    assert any(s.startswith("images/patch_") for s in srcs), "no style patch in the gallery"


def test_page_reads_in_words_and_tables(report_dir):
    page = (report_dir / "report.html").read_text()
    rep = json.loads((report_dir / "report.json").read_text())
    summary = re.search(r"<p class='lead' id='summary'>(.*?)</p>", page, re.S).group(1)
    k = len(rep["clusters"])
    assert summary.startswith(f"8 shapes, {k} style cluster") and "labelled" in summary
    assert "Clusters against the given labels" in page and "Clusters against the ground truth" in page
    assert "Least sure" in page and page.count("<figure>") == len(rep["shapes"])


def test_screenshot_shows_the_map_and_the_style_regions(report_dir, tmp_path):
    shot = tmp_path / "shot.png"
    res = run_chromium(tmp_path, "--hide-scrollbars", "--window-size=1200,3000",
                       f"--screenshot={shot}", (report_dir / "report.html").as_uri())
    assert shot.is_file(), res.stderr[-2000:]
    rgb = np.asarray(Image.open(shot).convert("RGB")).astype(int)
    # the first cluster's colour (the map's dots and legend) and the orange of style regions and boxes
    blue = (np.abs(rgb - [0, 114, 178]).sum(axis=2) < 30).sum()
    orange = ((rgb[..., 0] > 200) & (np.abs(rgb[..., 1] - 140) < 40) & (rgb[..., 2] < 80)).sum()
    assert blue > 100 and orange > 100, (blue, orange)
