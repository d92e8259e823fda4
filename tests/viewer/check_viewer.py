#!/usr/bin/env python3
"""Runs sparsebody_demo --html on a clip and checks the page in headless Chromium.

1. The page (--dump-dom) reports what its scene holds: frame count and joint positions at a few
   frames. They must match forward kinematics of the BVH the demo wrote (-o) within TOL_M, and the
   ground-truth figure must be the input clip's frame the page names (up to the clip's unit scale,
   the floor and the side-by-side offset, which are fitted).
2. A screenshot at a known frame: the avatar's colour must be where the reported camera projects
   its head and feet (the feet magenta exactly when the page says they are in contact), the clip's
   colour at its top joint, no avatar colour above the head or away from the avatar, the grid's
   colour at whole-metre crossings of y = 0, and enough avatar pixels to prove it drew.
3. Self-contained: no <script src>/<link>/<img>, and the page loaded no resources.

Exit 0 pass, 1 fail, 77 skip (no Chromium). --expect-fail TAMPER breaks the page on purpose
(no-render: never draws; shift: the avatar 30 cm off its data; draw-offset: the data
right but the avatar drawn 30 cm off; floor-high: the grid 30 cm above y = 0) and passes only if a check fails.
"""
import argparse
import html
import json
import os
import re
import shutil
import subprocess
import sys
import tempfile

import numpy as np

ROOT = os.path.dirname(os.path.dirname(os.path.dirname(os.path.abspath(__file__))))
sys.path.insert(0, ROOT)
from weights_tool.lobstr import bvh as bvhlib  # noqa: E402

TOL_M = 0.002  # page vs BVH: mm quantisation (0.5 mm) plus the BVH's 6 significant digits
WINDOW = (1000, 700)
CANVAS = (740, 600)  # right of the page's 260 px panel
CHROMIUM_FLAGS = ["--headless", "--no-sandbox", "--use-angle=swiftshader", "--enable-unsafe-swiftshader",
                  "--hide-scrollbars", "--disable-gpu-sandbox", "--no-first-run", "--mute-audio",
                  f"--window-size={WINDOW[0]},{WINDOW[1]}", "--force-device-scale-factor=1",
                  "--virtual-time-budget=4000"]


class CheckFailed(Exception):
    pass


def check(cond, msg):
    if not cond:
        raise CheckFailed(msg)


def find_chromium():
    for c in [os.environ.get("SPARSEBODY_CHROMIUM"), "chromium", "chromium-browser", "google-chrome"]:
        if c and shutil.which(c):
            return shutil.which(c)
    return None


def run_chromium(chromium, args, url, profile):
    cmd = [chromium] + CHROMIUM_FLAGS + [f"--user-data-dir={profile}"] + args + [url]
    r = subprocess.run(cmd, capture_output=True, text=True, timeout=120)
    if r.returncode != 0:
        raise CheckFailed(f"chromium exited {r.returncode}: {r.stderr[-500:]}")
    return r.stdout


def page_report(dom):
    m = re.search(r'<pre id="sb-report"[^>]*>(.*?)</pre>', dom, re.S)
    check(m and m.group(1).strip(), "the page wrote no report (its script did not run to the end)")
    return json.loads(html.unescape(m.group(1)))


def bvh_positions(path):
    """World joint positions [F, J, 3] in metres of the demo's output BVH (centimetres)."""
    b = bvhlib.load(path)
    R, t = bvhlib.local_transforms(b)
    _, p = bvhlib.fk(b.parents, R, t)
    return b, p / 100.0


def check_positions(rep, out_bvh):
    b, P = bvh_positions(out_bvh)
    check(rep["frames"] == b.frames, f"page has {rep['frames']} frames, the BVH {b.frames}")
    idx = [b.index(n) for n in rep["avatar"]["names"]]
    worst = 0.0
    for pr in rep["probes"]:
        got = np.array(pr["avatar"])
        want = P[pr["frame"], idx]
        err = np.linalg.norm(got - want, axis=1).max()
        worst = max(worst, err)
        check(err <= TOL_M, f"frame {pr['frame']}: page joints are up to {100 * err:.2f} cm from the BVH's FK (tolerance {100 * TOL_M} cm)")
    # the shown frame's joints, which the screenshot check projects
    err = np.linalg.norm(np.array(rep["avatar"]["positions"]) - P[rep["frame"], idx], axis=1).max()
    check(err <= TOL_M, f"shown frame {rep['frame']}: page joints are up to {100 * err:.2f} cm from the BVH's FK")
    return max(worst, err)


def check_truth(rep, clip_path):
    """The ground-truth figure is the clip's frame truth_frame: fit scale, floor and offset."""
    clip = bvhlib.load(clip_path)
    R, t = bvhlib.local_transforms(clip)
    _, P = bvhlib.fk(clip.parents, R, t)
    idx = [clip.index(n) for n in rep["truth"]["names"]]
    worst = 0.0
    for pr in rep["probes"]:
        got, raw = np.array(pr["truth"]), P[pr["truth_frame"], idx]
        # got = s * raw + c: s the clip's units, c the floor (y) and side-by-side offset (x).
        A = np.concatenate([raw.reshape(-1, 1), np.tile(np.eye(3), (len(idx), 1))], axis=1)
        sol, *_ = np.linalg.lstsq(A, got.reshape(-1), rcond=None)
        err = np.linalg.norm((A @ sol).reshape(-1, 3) - got, axis=1).max()
        worst = max(worst, err)
        check(err <= TOL_M and 0.001 < sol[0] < 1.0, f"frame {pr['frame']}: the clip figure is not clip frame {pr['truth_frame']} "
              f"(residual {100 * err:.2f} cm, scale {sol[0]:.4f})")
        check(abs(sol[1] - rep["gt_offset"]) < 0.5 or rep["gt_mode"] != "side", "the clip figure is not offset sideways")
    return worst


def project(rep, p):
    """Screen pixel (x, y) of world point p with the camera the page reports."""
    V = np.array(rep["camera"]["view"]).reshape(4, 4).T  # three.js stores column-major
    Pm = np.array(rep["camera"]["projection"]).reshape(4, 4).T
    c = Pm @ V @ np.append(p, 1.0)
    ndc = c[:3] / c[3]
    cv = rep["canvas"]
    r = cv["pixel_ratio"]
    return ((cv["left"] + (ndc[0] + 1) / 2 * cv["width"]) * r, (cv["top"] + (1 - ndc[1]) / 2 * cv["height"]) * r)


def colour_mask(img, hexcol, tol=40):
    c = np.array([(hexcol >> 16) & 255, (hexcol >> 8) & 255, hexcol & 255])
    return np.all(np.abs(img.astype(int) - c) <= tol, axis=2)


def frac_near(mask, xy, r=3):
    x, y = int(round(xy[0])), int(round(xy[1]))
    h, w = mask.shape
    if not (0 <= x < w and 0 <= y < h):
        return 0.0
    win = mask[max(0, y - r):y + r + 1, max(0, x - r):x + r + 1]
    return float(win.mean())


def check_screenshot(rep, png):
    import matplotlib
    matplotlib.use("Agg")
    import matplotlib.pyplot as plt
    img = plt.imread(png)
    img = (img[..., :3] * 255).round().astype(np.uint8) if img.dtype != np.uint8 else img[..., :3]
    check(img.shape[1] == WINDOW[0] and img.shape[0] == WINDOW[1], f"screenshot is {img.shape[1]}x{img.shape[0]}, expected {WINDOW}")
    col = rep["colors"]
    cv = rep["canvas"]
    left = int(np.ceil(cv["left"] * cv["pixel_ratio"]))
    orange, magenta, blue = (colour_mask(img, col[k]) for k in ("avatar", "contact", "truth"))
    orange[:, :left] = magenta[:, :left] = blue[:, :left] = False  # the panel's colour key
    body = orange | magenta
    a = rep["avatar"]
    pos = np.array(a["positions"])
    n = int(body.sum())
    check(n > 400, f"only {n} avatar pixels: the page did not draw the avatar")
    head = project(rep, pos[a["head"]])
    check(frac_near(orange, head) > 0.6, f"no avatar colour at the head's projection {head[0]:.0f},{head[1]:.0f}")
    foot_px = abs(project(rep, pos[a["feet"][0][1]] + np.array([0, 0.045, 0]))[1] - project(rep, pos[a["feet"][0][1]])[1])
    checked = 0
    for s, side in enumerate("LR"):
        want = magenta if a["contacts"][s] else orange
        for j in a["feet"][s]:
            xy = project(rep, pos[j])
            # feet are drawn over the legs; only the other foot, in the other state, can cover this one
            other = [project(rep, pos[k]) for k in a["feet"][1 - s]]
            if a["contacts"][0] != a["contacts"][1] and min(np.hypot(o[0] - xy[0], o[1] - xy[1]) for o in other) < foot_px + 4:
                continue
            check(frac_near(want, xy, 2) > 0.5, f"foot {side} joint {a['names'][j]} at {xy[0]:.0f},{xy[1]:.0f} is not "
                  f"{'magenta (in contact)' if a['contacts'][s] else 'the avatar colour (no contact)'}")
            checked += 1
    check(checked >= 2, "the feet overlap on screen: choose another --frame")
    above = project(rep, pos[a["head"]] + np.array([0, 0.45, 0]))
    check(frac_near(body, above, 4) == 0, "avatar colour 45 cm above the head")
    # every avatar pixel lies near the projected joints (the figure is where the data says)
    pts = np.array([project(rep, p) for p in pos])
    margin = 0.6 * abs(project(rep, pos[a["head"]] + np.array([0, 0.1, 0]))[1] - head[1]) + 12
    ys, xs = np.nonzero(body)
    outside = ((xs < pts[:, 0].min() - margin) | (xs > pts[:, 0].max() + margin) |
               (ys < pts[:, 1].min() - margin - 2 * margin) | (ys > pts[:, 1].max() + margin))
    check(outside.sum() <= 0.01 * n, f"{int(outside.sum())} avatar pixels away from where its joints project")
    # the floor: whole-metre grid crossings at y = 0 (away from the figures) show the grid's colour
    grid = colour_mask(img, col["grid"], 30)
    figures = list(pts) + ([project(rep, p) for p in rep["truth"]["positions"]] if rep["truth"] else [])
    figures += [project(rep, np.array(t["position"])) for t in rep["trackers"] if t["visible"]]
    cx, cz = np.round(np.array(rep["camera"]["target"])[[0, 2]])
    seen = tried = 0
    for gx in np.arange(cx - 3, cx + 4):
        for gz in np.arange(cz - 3, cz + 2):
            if abs(gx) < 0.5 or abs(gz) < 0.5:
                continue  # the axes have their own colour
            xy = project(rep, np.array([gx, 0.0, gz]))
            if not (left + 5 < xy[0] < img.shape[1] - 5 and 5 < xy[1] < img.shape[0] - 5):
                continue
            if min(np.hypot(f[0] - xy[0], f[1] - xy[1]) for f in figures) < 40:
                continue
            tried += 1
            seen += frac_near(grid, xy, 2) > 0
    check(tried >= 5 and seen >= 0.8 * tried, f"the floor grid is not at y = 0: {seen} of {tried} grid crossings seen")
    if rep["truth"] and rep["truth"]["visible"]:
        t = np.array(rep["truth"]["positions"])
        top = t[np.argmax(t[:, 1])]
        xy = project(rep, top)
        check(frac_near(blue, xy, 3) > 0.3, f"no clip colour at its top joint's projection {xy[0]:.0f},{xy[1]:.0f}")
        check(frac_near(body, xy, 3) == 0, "avatar colour where the clip figure is")
    return n, head, (seen, tried)


TAMPER = {
    "no-render": ("function render() { renderer.render(scene, camera); }", "function render() {}"),
    "shift": ("this.joints[j].position.set(pos[o] / 1000,", "this.joints[j].position.set(pos[o] / 1000 + 0.3,"),
    "floor-high": ("g.setAttribute('position', new THREE.BufferAttribute(new Float32Array(v), 3));",  # grid 30 cm up
                   "g.setAttribute('position', new THREE.BufferAttribute(new Float32Array(v), 3)); g.translate(0, 0.3, 0);"),
    "draw-offset": ("function render() { renderer.render(scene, camera); }",  # data right, picture 30 cm off
                    "function render() { avatar.group.position.x = 0.3; renderer.render(scene, camera); avatar.group.position.x = 0; }"),
}


def main():
    ap = argparse.ArgumentParser()
    ap.add_argument("--demo", required=True)
    ap.add_argument("--clip", required=True)
    ap.add_argument("--out", required=True, help="folder for the page, BVH and screenshot")
    ap.add_argument("--frame", type=int, default=None, help="screenshot frame (default: a third of the clip)")
    ap.add_argument("--revision", default=None, help="three.js revision the page must report")
    ap.add_argument("--expect-fail", choices=sorted(TAMPER), default=None)
    ap.add_argument("demo_args", nargs="*", help="more demo options (after --)")
    a = ap.parse_args()
    chromium = find_chromium()
    if not chromium:
        print("SKIP: no chromium (apt-get install chromium; .ci/install-deps.sh does)")
        return 77
    os.makedirs(a.out, exist_ok=True)
    page, out_bvh, png = (os.path.join(a.out, f) for f in ("viewer.html", "avatar.bvh", "frame.png"))
    cmd = [a.demo, a.clip, "-o", out_bvh, "--html", page, "--quiet"] + a.demo_args
    r = subprocess.run(cmd, capture_output=True, text=True)
    print(r.stdout, r.stderr, sep="")
    if r.returncode != 0:
        print(f"FAIL: the demo exited {r.returncode}")
        return 1
    if a.expect_fail:
        old, new = TAMPER[a.expect_fail]
        text = open(page, encoding="utf-8").read()
        assert old in text, f"tamper '{a.expect_fail}': the template changed, update TAMPER"
        with open(page, "w", encoding="utf-8") as f:
            f.write(text.replace(old, new))
    try:
        text = open(page, encoding="utf-8").read()
        check(not re.search(r"<(script|img|iframe|link)\b[^>]*\b(src|href)\s*=", text, re.I), "the page references an external file")
        size = os.path.getsize(page)
        with tempfile.TemporaryDirectory() as profile:
            _, b = bvh_positions(out_bvh)
            frame = a.frame if a.frame is not None else b.shape[0] // 3
            # a fixed canvas: headless --dump-dom's viewport is shorter than --screenshot's
            url = "file://" + os.path.abspath(page) + f"?frame={frame}&size={CANVAS[0]}x{CANVAS[1]}"
            rep = page_report(run_chromium(chromium, ["--dump-dom"], url, profile))
            check(rep.get("ok"), f"the page failed: {rep.get('error')}")
            check(not rep["errors"], f"script errors in the page: {rep['errors']}")
            check(rep["resources"] == [], f"the page loaded resources: {rep['resources']}")
            check(rep["frame"] == frame, f"page shows frame {rep['frame']}, asked for {frame}")
            if a.revision:
                check(str(rep["revision"]) == a.revision, f"three.js r{rep['revision']}, expected r{a.revision}")
            err = check_positions(rep, out_bvh)
            terr = check_truth(rep, a.clip) if rep["truth"] else None
            run_chromium(chromium, [f"--screenshot={png}"], url, profile)
            n, head, grid = check_screenshot(rep, png)
    except CheckFailed as e:
        if a.expect_fail:
            print(f"PASS: the broken page ('{a.expect_fail}') is caught: {e}")
            return 0
        print(f"FAIL: {e}")
        return 1
    if a.expect_fail:
        print(f"FAIL: the broken page ('{a.expect_fail}') passed every check")
        return 1
    print(f"PASS: {page} ({size / 1e6:.2f} MB, three.js r{rep['revision']}): {rep['frames']} frames; page vs BVH FK max "
          f"{1000 * err:.2f} mm" + (f", clip figure residual {1000 * terr:.2f} mm" if terr is not None else "") +
          f" (tolerance {1000 * TOL_M:.0f} mm); frame {frame}: {n} avatar pixels, head at {head[0]:.0f},{head[1]:.0f}, "
          f"contacts L {rep['avatar']['contacts'][0]} R {rep['avatar']['contacts'][1]}, grid crossings {grid[0]}/{grid[1]}")
    return 0


if __name__ == "__main__":
    sys.exit(main())
