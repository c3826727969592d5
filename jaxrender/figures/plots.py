"""One pure function per figure: prepared data in, a matplotlib Figure out.

Nothing here computes a metric or reads a file; ``jaxrender.figures.data`` prepares the
inputs from a run directory. Equal inputs give byte-equal files through ``save_figure``.
"""

from __future__ import annotations

import math

import numpy as np
from matplotlib.colors import ListedColormap
from matplotlib.figure import Figure
from matplotlib.patches import Rectangle

from jaxrender.figures.io import new_figure, style


def _footer(fig: Figure, device: str) -> None:
    if device:
        fig.text(0.995, 0.002, device, ha="right", va="bottom", fontsize=5, color="0.4")


def _row_label(label: str) -> str:
    """A variant's row label with its parameters on a second line: rows of small images are
    shorter than "tads_every2 shade_every=2", and one-line labels ran into their neighbours."""
    return label.replace(" ", "\n", 1)


def _off(ax) -> None:
    ax.set_xticks([])
    ax.set_yticks([])
    ax.grid(False)
    for s in ax.spines.values():
        s.set_visible(False)


def fig_image_grid(panel: dict) -> Figure:
    """Reference, each pipeline, its error map and a zoomed crop of the hardest region.

    panel: {title, device, reference: (H,W,3) display-referred, crop: (y0, x0, h, w), error_max: float,
            entries: [{label, image: (H,W,3) display-referred, error: (H,W), caption}]}"""
    entries = panel["entries"]
    y0, x0, ch, cw = panel["crop"]
    h, w = panel["reference"].shape[:2]
    rows = len(entries) + 1
    col_w = 2.2
    with style():
        fig = new_figure(3 * col_w, rows * col_w * h / max(w, 1) + 0.5)
        axes = fig.subplots(rows, 3, squeeze=False)
        vmax = panel.get("error_max") or 1.0
        items = [("reference", panel["reference"], None, "")] + [
            (e["label"], e["image"], e["error"], e.get("caption", "")) for e in entries]
        im = None
        for r, (label, img, err, caption) in enumerate(items):
            a_img, a_err, a_crop = axes[r]
            a_img.imshow(img)
            a_img.add_patch(Rectangle((x0 - 0.5, y0 - 0.5), cw, ch, fill=False, ec="#ff00ff",
                                      lw=0.8))
            if caption:
                a_img.set_title(caption, fontsize=6, loc="left")
            if err is not None:
                im = a_err.imshow(err, cmap="magma", vmin=0.0, vmax=vmax)
            a_crop.imshow(img[y0:y0 + ch, x0:x0 + cw])
            for a in (a_img, a_err, a_crop):
                _off(a)
            a_img.set_ylabel(_row_label(label), fontsize=7)
        axes[0][0].set_title("image", fontsize=7)
        axes[0][1].set_title("error map", fontsize=7)
        axes[0][2].set_title("hardest region (zoom)", fontsize=7)
        if im is not None:
            fig.colorbar(im, ax=[row[1] for row in axes], location="bottom", shrink=0.9,
                         aspect=30, label="error")
        fig.suptitle(panel["title"])
        _footer(fig, panel.get("device", ""))
    return fig


def fig_pareto(table: dict) -> Figure:
    """Accuracy against cost: one marker per sweep point, the points of one pipeline entry
    joined in sweep order, and the Pareto front of all points dashed.

    table: {title, xlabel, ylabel, logx, device, series: [{label, x: [...], y: [...]}],
            front: [(x, y), ...]}"""
    with style():
        fig = new_figure(4.2, 3.0)
        ax = fig.subplots()
        for s in table["series"]:
            ax.plot(s["x"], s["y"], marker="o", label=s["label"])
        if table.get("front"):
            fx, fy = zip(*table["front"])
            ax.plot(fx, fy, ls="--", color="0.35", lw=0.8, drawstyle="steps-post",
                    label="Pareto front", zorder=0)
        if table.get("logx"):
            ax.set_xscale("log")
        ax.set_xlabel(table["xlabel"])
        ax.set_ylabel(table["ylabel"])
        ax.set_title(table["title"])
        ax.legend(loc="best")
        _footer(fig, table.get("device", ""))
    return fig


def fig_temporal(table: dict) -> Figure:
    """Temporal error (flicker the reference does not have) and PSNR over the frames.

    table: {title, device, series: [{label, frames, temporal, psnr}]}"""
    with style():
        fig = new_figure(4.6, 3.6)
        top, bottom = fig.subplots(2, 1, sharex=True)
        for s in table["series"]:
            top.plot(s["frames"], s["temporal"], marker=".", label=s["label"])
            bottom.plot(s["frames"], s["psnr"], marker=".", label=s["label"])
        top.set_ylabel("temporal error")
        bottom.set_ylabel("PSNR (dB)")
        bottom.set_xlabel("frame")
        top.set_title(table["title"])
        top.legend(loc="best")
        _footer(fig, table.get("device", ""))
    return fig


_LEVEL_COLOURS = ["#222222", "#0072B2", "#56B4E9", "#009E73", "#E69F00", "#D55E00", "#CC79A7"]


def fig_dacs_decisions(table: dict) -> Figure:
    """Shading decisions (DACS): per pipeline variant the image, the level at which each pixel
    was decided and whether it was shaded (white) or interpolated.

    table: {title, device, entries: [{label, image: (H,W,3) display-referred,
            level: (H,W) int or None, shaded: (H,W) bool or None}]}"""
    entries = table["entries"]
    h, w = entries[0]["image"].shape[:2]
    with style():
        fig = new_figure(3 * 2.0, len(entries) * 2.0 * h / max(w, 1) + 0.6)
        axes = fig.subplots(len(entries), 3, squeeze=False)
        for row, e in zip(axes, entries):
            row[0].imshow(e["image"])
            if e.get("level") is not None:
                m = np.asarray(e["level"])
                n = int(np.clip(m.max() + 1, 2, len(_LEVEL_COLOURS)))
                row[1].imshow(m, cmap=ListedColormap(_LEVEL_COLOURS[:n]), vmin=0, vmax=n - 1)
                row[1].set_title(f"decision level (0..{n - 1})", fontsize=7)
            if e.get("shaded") is not None:
                m = np.asarray(e["shaded"], np.float32)
                row[2].imshow(m, cmap="gray", vmin=0, vmax=1)
                row[2].set_title(f"shaded: {float(np.mean(m)):.1%}", fontsize=7)
            for ax in row:
                _off(ax)
            row[0].set_ylabel(_row_label(e["label"]), fontsize=7)
        fig.suptitle(table["title"])
        _footer(fig, table.get("device", ""))
    return fig


def fig_object_space_marking(table: dict) -> Figure:
    """Object-space chunk marking as Oxide shows it: green for any chunk hit, blue for fully
    visible sections; beside it the MIP level each pixel selected.

    table: {title, device, entries: [{label, image, chunk_state: (Y,X) int 0 none / 1 hit /
            2 fully visible, mip_level: (H,W) or None}]}"""
    entries = table["entries"]
    h, w = entries[0]["image"].shape[:2]
    cmap = ListedColormap(["#202020", "#2ca02c", "#1f77b4"])
    with style():
        fig = new_figure(3 * 2.0, len(entries) * 2.0 * h / max(w, 1) + 0.6)
        axes = fig.subplots(len(entries), 3, squeeze=False)
        for row, e in zip(axes, entries):
            row[0].imshow(e["image"])
            row[1].imshow(np.asarray(e["chunk_state"]), cmap=cmap, vmin=0, vmax=2)
            row[1].set_title("chunks: green hit, blue fully visible", fontsize=6)
            if e.get("mip_level") is not None:
                row[2].imshow(np.asarray(e["mip_level"], np.float32), cmap="viridis")
                row[2].set_title("MIP level", fontsize=7)
            for ax in row:
                _off(ax)
            row[0].set_ylabel(_row_label(e["label"]), fontsize=7)
        fig.suptitle(table["title"])
        _footer(fig, table.get("device", ""))
    return fig


def fig_tads_samples(table: dict) -> Figure:
    """Texture-aligned deferred shading's unique samples: per variant the image, how many
    texels each pixel shades after the north / north-west / west rule (its sample class: 0,
    1, 2, 3, 4 or more with anisotropic taps) and how many of them some other pixel shades
    too (the duplicates the rule misses).

    table: {title, device, entries: [{label, image, sample_class: (H,W) int, -1 uncovered,
            duplicates: (H,W) int or None}]}"""
    entries = table["entries"]
    h, w = entries[0]["image"].shape[:2]
    colours = ["#000000", "#404040", "#1f77b4", "#2ca02c", "#ff7f0e", "#d62728"]
    names = ["none", "0", "1", "2", "3", "4+"]
    with style():
        fig = new_figure(3 * 2.0, len(entries) * 2.0 * h / max(w, 1) + 0.8)
        axes = fig.subplots(len(entries), 3, squeeze=False)
        for row, e in zip(axes, entries):
            row[0].imshow(e["image"])
            m = np.clip(np.asarray(e["sample_class"], np.int32), -1, 4)
            row[1].imshow(m + 1, cmap=ListedColormap(colours), vmin=0, vmax=5,
                          interpolation="nearest")
            cov = m[m >= 0]
            share = [float(np.mean(cov == k)) if cov.size else 0.0 for k in range(5)]
            row[1].set_title("texels shaded 0/1/2/3/4+: " + " ".join(f"{v:.0%}" for v in share),
                             fontsize=5)
            if e.get("duplicates") is not None:
                d = np.asarray(e["duplicates"], np.float32)
                row[2].imshow(d, cmap="magma", vmin=0, vmax=max(float(d.max()), 1.0),
                              interpolation="nearest")
                row[2].set_title(f"texels also shaded by another pixel: {int(np.sum(d))}",
                                 fontsize=5)
            for ax in row:
                _off(ax)
            row[0].set_ylabel(_row_label(e["label"]), fontsize=7)
        fig.legend([Rectangle((0, 0), 1, 1, color=c) for c in colours], names,
                   loc="outside lower center", ncol=len(names), fontsize=6,
                   title="sample class (texels a pixel shades)", title_fontsize=6,
                   frameon=False)
        fig.suptitle(table["title"])
        _footer(fig, table.get("device", ""))
    return fig


def fig_visbuffer_waves(table: dict) -> Figure:
    """Visibility-buffer shading waves and their lane utilisation per variant.

    table: {title, device, labels: [...], waves: [...], utilization: [...]}"""
    labels = table["labels"]
    x = np.arange(len(labels))
    with style():
        fig = new_figure(max(3.5, 0.7 * len(labels) + 2), 3.2)
        left, right = fig.subplots(1, 2)
        left.bar(x, table["waves"], color="#0072B2")
        left.set_ylabel("waves")
        right.bar(x, [100.0 * u for u in table["utilization"]], color="#009E73")
        right.set_ylabel("lane utilisation (%)")
        right.set_ylim(0, 100)
        for ax in (left, right):
            ax.set_xticks(x, labels, rotation=35, ha="right")
        fig.suptitle(table["title"])
        _footer(fig, table.get("device", ""))
    return fig


def _cell(v) -> str:
    if isinstance(v, float):
        if math.isnan(v):
            return "-"
        return f"{v:,.0f}" if abs(v) >= 1000 else f"{v:.4g}"
    return str(v)


def fig_summary_table(table: dict) -> Figure:
    """The summary table as a figure. table: {title, device, columns: [...], rows: [[...]]}"""
    rows = [[_cell(v) for v in r] for r in table["rows"]]
    with style():
        fig = new_figure(1.1 * len(table["columns"]) + 1.5, 0.28 * (len(rows) + 1) + 0.6)
        ax = fig.subplots()
        ax.axis("off")
        t = ax.table(cellText=rows or [["-"] * len(table["columns"])],
                     colLabels=table["columns"], loc="center", cellLoc="right")
        t.auto_set_font_size(False)
        t.set_fontsize(7)
        # Columns as wide as their text: at equal widths long variant labels were cut off.
        t.auto_set_column_width(list(range(len(table["columns"]))))
        t.scale(1.0, 1.2)
        ax.set_title(table["title"])
        _footer(fig, table.get("device", ""))
    return fig


def fig_time_work(table: dict) -> Figure:
    """Frame time against shading work per pipeline variant: the measured points, the fitted
    line (dashed where the series failed the linearity check) and a cross where a pipeline
    becomes faster than the baseline, labelled with that shader cost.

    table: {title, xlabel, ylabel, baseline, log, device, series: [{label, work, time,
            line_work, line_time, linear}], crossings: [{label, cost, work, time}]}"""
    with style():
        fig = new_figure(5.0, 3.6)
        ax = fig.subplots()
        colours = {}
        for s in table["series"]:
            (pts,) = ax.plot(s["work"], s["time"], marker="o", ls="none", label=s["label"])
            colours[s["label"]] = pts.get_color()
            ax.plot(s["line_work"], s["line_time"], color=pts.get_color(), lw=0.9,
                    ls="-" if s["linear"] else "--")
        for c in table["crossings"]:
            ax.plot([c["work"]], [c["time"]], marker="X", ms=7, color=colours.get(c["label"]),
                    mec="black", mew=0.5, ls="none")
            ax.annotate(f"{c['label']} < {table['baseline']}\nfrom cost {c['cost']:.3g}",
                        (c["work"], c["time"]), xytext=(4, -10), textcoords="offset points",
                        fontsize=5)
        if table.get("log"):
            ax.set_xscale("log")
            ax.set_yscale("log")
        ax.set_xlabel(table["xlabel"])
        ax.set_ylabel(table["ylabel"])
        ax.set_title(table["title"])
        ax.legend(loc="upper left", fontsize=5)
        _footer(fig, table.get("device", ""))
    return fig
