#!/usr/bin/env python3
"""plot_eval.py: the plots of `cenote eval`, drawn from the numbers cenote wrote as JSON.

Usage: plot_eval.py METRICS.json OUT_DIR
The JSON's "kind" is "depth", "cloud" or "trajectory" (the documents `cenote eval ... --json`
writes). Writes PNG files into OUT_DIR and prints one line per file. Needs python3-matplotlib and
python3-numpy (Debian). cenote embeds this script and runs it with /usr/bin/python3.
"""
import json
import os
import sys

import matplotlib

matplotlib.use("Agg")
import matplotlib.pyplot as plt  # noqa: E402
import matplotlib.ticker  # noqa: E402
import numpy as np  # noqa: E402

DPI = 110


def save(fig, out_dir, name):
    path = os.path.join(out_dir, name)
    fig.tight_layout()
    fig.savefig(path, dpi=DPI)
    plt.close(fig)
    print(path)


def trimmed(hist):
    """Edges and counts of a log histogram without its empty ends."""
    counts = np.asarray(hist["counts"], dtype=float)
    edges = np.asarray(hist["edges"], dtype=float)
    nonzero = np.nonzero(counts)[0]
    if len(nonzero) == 0:
        return None, None
    lo, hi = nonzero[0], nonzero[-1] + 1
    return edges[lo:hi + 1], counts[lo:hi]


def read_pfm(path):
    with open(path, "rb") as f:
        magic = f.readline().strip()
        width, height = map(int, f.readline().split())
        scale = float(f.readline())
        channels = 3 if magic == b"PF" else 1
        data = np.fromfile(f, "<f4" if scale < 0 else ">f4", width * height * channels)
    data = data.reshape(height, width, channels) if channels == 3 else data.reshape(height, width)
    return np.flipud(data)


def fmt_m(value):
    return "n/a" if value is None else f"{value:.4g} m"


def plot_log_histograms(ax, series, xlabel):
    for label, hist, color in series:
        edges, counts = trimmed(hist)
        if edges is None:
            continue
        fraction = counts / max(counts.sum(), 1.0) * 100.0
        ax.stairs(fraction, edges, fill=True, alpha=0.35, color=color)
        ax.stairs(fraction, edges, label=label, color=color, linewidth=1.5)
    ax.set_xscale("log")
    ax.set_xlabel(xlabel)
    ax.set_ylabel("share of points per bin [%]")
    ax.grid(True, which="both", alpha=0.3)


def depth_plots(doc, out_dir):
    fig, ax = plt.subplots(figsize=(7, 4.2))
    plot_log_histograms(ax, [("|estimate - reference|", doc["histogram"], "tab:blue")], "absolute depth error [m]")
    for value, label, style in ((doc.get("mae"), "MAE", "--"), (doc.get("mom"), "MoM", ":")):
        if value:
            ax.axvline(value, color="black", linestyle=style, label=f"{label} = {value:.4g} m")
    ax.set_title(f"Depth error over {doc['frames_matched']} frames ({doc['common_px']} pixels compared)")
    ax.legend()
    save(fig, out_dir, "depth_error_histogram.png")

    frames = doc["frames"]
    if frames:
        fig, ax = plt.subplots(figsize=(8, 4.2))
        x = np.arange(len(frames))
        mean = np.array([f["mean_abs_m"] if f["mean_abs_m"] is not None else np.nan for f in frames], dtype=float)
        median = np.array([f["median_abs_m"] if f["median_abs_m"] is not None else np.nan for f in frames], dtype=float)
        ax.plot(x, mean, "o-" if len(frames) < 60 else "-", label="per-frame mean", color="tab:blue")
        ax.plot(x, median, "s-" if len(frames) < 60 else "-", label="per-frame median", color="tab:orange")
        ax2 = ax.twinx()
        ax2.plot(x, [100.0 * f["coverage"] for f in frames], color="tab:green", alpha=0.5, label="coverage")
        ax2.set_ylabel("coverage [%]", color="tab:green")
        ax2.set_ylim(0, 105)
        ax.set_xlabel("frame (sorted by name)")
        ax.set_ylabel("absolute depth error [m]")
        top = np.nanmax(np.concatenate([mean, median])) if np.isfinite(np.concatenate([mean, median])).any() else 1.0
        ax.set_ylim(0, 1.15 * top if top > 0 else 1.0)
        ax.ticklabel_format(axis="y", useOffset=False)
        ax.xaxis.set_major_locator(matplotlib.ticker.MaxNLocator(integer=True))
        ax.set_title("Depth error per frame")
        ax.grid(True, alpha=0.3)
        lines = ax.get_legend_handles_labels()
        lines2 = ax2.get_legend_handles_labels()
        ax.legend(lines[0] + lines2[0], lines[1] + lines2[1], loc="upper left")
        save(fig, out_dir, "depth_error_per_frame.png")

    for sample in doc.get("heatmaps", []):
        error = read_pfm(sample["error_pfm"])
        finite = error[np.isfinite(error)]
        vmax = float(np.percentile(finite, 99)) if finite.size else 1.0
        panels = [("reference depth [m]", sample.get("reference_pfm"), "viridis", None),
                  ("|error| [m]", sample["error_pfm"], "inferno", vmax)]
        panels = [p for p in panels if p[1]]
        fig, axes = plt.subplots(1, len(panels), figsize=(5.2 * len(panels), 4.2), squeeze=False)
        for ax, (title, path, cmap, top) in zip(axes[0], panels):
            image = read_pfm(path)
            masked = np.ma.masked_invalid(image)
            cm = matplotlib.colormaps[cmap].copy()
            cm.set_bad("lightgrey")
            shown = ax.imshow(masked, cmap=cm, vmin=0 if top else None, vmax=top)
            fig.colorbar(shown, ax=ax, fraction=0.046, pad=0.04)
            ax.set_title(title)
            ax.set_axis_off()
        fig.suptitle(f"{sample['name']}: mean {fmt_m(sample.get('mean_abs_m'))}, "
                     f"median {fmt_m(sample.get('median_abs_m'))} (grey: not compared)")
        save(fig, out_dir, f"depth_error_{sample['name']}.png")


def cloud_plots(doc, out_dir):
    curve = doc["curve"]
    t = np.array([c["threshold_m"] for c in curve])
    fig, ax = plt.subplots(figsize=(7, 4.5))
    ax.plot(t, [100 * c["precision"] for c in curve], label="precision (source → target)", color="tab:blue", lw=2)
    ax.plot(t, [100 * c["recall"] for c in curve], label="recall (target → source)", color="tab:orange", lw=2)
    ax.plot(t, [100 * c["fscore"] for c in curve], label="F-score", color="tab:gray", lw=1.2, ls="--")
    ax.axvline(doc["threshold"], color="black", ls=":",
               label=f"{doc['threshold']:g} m: P {100 * doc['precision']:.1f} %, R {100 * doc['recall']:.1f} %")
    ax.set_xlabel("distance threshold [m]")
    ax.set_ylabel("points within the threshold [%]")
    ax.set_ylim(0, 101)
    ax.set_xlim(0, t[-1])
    ax.grid(True, alpha=0.3)
    ax.legend(loc="lower right")
    ax.set_title(f"Precision and recall against the threshold ({doc['source_points']} / {doc['target_points']} points)")
    save(fig, out_dir, "cloud_precision_recall.png")

    fig, ax = plt.subplots(figsize=(7, 4.2))
    plot_log_histograms(ax, [("source → target", doc["source_histogram"], "tab:blue"),
                             ("target → source", doc["target_histogram"], "tab:orange")],
                        "nearest-neighbour distance [m]")
    ax.axvline(doc["threshold"], color="black", ls=":", label=f"threshold {doc['threshold']:g} m")
    ax.set_title(f"Distances: accuracy {doc['accuracy']:.4g} m, completeness {doc['completeness']:.4g} m")
    ax.legend()
    save(fig, out_dir, "cloud_distance_histogram.png")


def trajectory_plots(doc, out_dir):
    traj = doc["trajectory"]
    ref = np.asarray(traj["reference"], dtype=float)
    est = np.asarray(traj["aligned"], dtype=float)
    if ref.size == 0:
        return
    extent = ref.max(axis=0) - ref.min(axis=0)
    a, b = sorted(np.argsort(extent)[::-1][:2])
    names = "xyz"
    fig, ax = plt.subplots(figsize=(6.5, 6))
    ax.plot(ref[:, a], ref[:, b], color="black", lw=2, label="reference")
    ax.plot(est[:, a], est[:, b], color="tab:red", lw=1.5, label=f"estimate ({doc['alignment']} aligned)")
    step = max(1, len(ref) // 40)
    for i in range(0, len(ref), step):
        ax.plot([ref[i, a], est[i, a]], [ref[i, b], est[i, b]], color="tab:gray", lw=0.6, alpha=0.7)
    ax.plot(ref[0, a], ref[0, b], "o", color="tab:green", label="start")
    ax.set_aspect("equal", adjustable="datalim")
    ax.set_xlabel(f"{names[a]} [m]")
    ax.set_ylabel(f"{names[b]} [m]")
    ax.grid(True, alpha=0.3)
    ax.legend()
    ax.set_title(f"Top view: ATE RMSE {doc['ate_rmse']:.4g} m over {doc['pairs']} poses")
    save(fig, out_dir, "trajectory_top_view.png")

    fig, ax = plt.subplots(figsize=(8, 3.8))
    t = np.asarray(traj["t_s"], dtype=float)
    ax.plot(t - t[0], traj["error_m"], color="tab:red")
    ax.axhline(doc["ate_rmse"], color="black", ls="--", label=f"RMSE {doc['ate_rmse']:.4g} m")
    ax.axhline(doc["ate_median"], color="black", ls=":", label=f"median {doc['ate_median']:.4g} m")
    ax.set_xlabel("time since the first pose [s]")
    ax.set_ylabel("position error [m]")
    ax.set_title("Absolute trajectory error over time")
    ax.grid(True, alpha=0.3)
    ax.legend()
    save(fig, out_dir, "trajectory_error.png")


def main():
    if len(sys.argv) != 3:
        sys.exit("usage: plot_eval.py METRICS.json OUT_DIR")
    with open(sys.argv[1]) as f:
        doc = json.load(f)
    os.makedirs(sys.argv[2], exist_ok=True)
    kinds = {"depth": depth_plots, "cloud": cloud_plots, "trajectory": trajectory_plots}
    if doc.get("kind") not in kinds:
        sys.exit(f"{sys.argv[1]}: unknown kind {doc.get('kind')!r}")
    kinds[doc["kind"]](doc, sys.argv[2])


if __name__ == "__main__":
    main()
