"""Offscreen pictures of the drawing with matplotlib's 3-D axes (no display
or OpenGL needed): one frame as PNG, or a GIF (Pillow) / MP4 (ffmpeg)."""
import pathlib
import shutil

import matplotlib

matplotlib.use("Agg")
import matplotlib.pyplot as plt  # noqa: E402
import numpy as np  # noqa: E402
from matplotlib import animation  # noqa: E402
from mpl_toolkits.mplot3d.art3d import Poly3DCollection  # noqa: E402

LIGHT = np.array([0.3, 0.4, 0.87]) / np.linalg.norm([0.3, 0.4, 0.87])


def _bounds(drawing, frames):
    """A cube around the world origin and the drawing at up to 24 of the
    frames, and the drawing's own extent along each axis."""
    frames = np.asarray(frames)[np.unique(np.linspace(0, len(frames) - 1, min(24, len(frames))).astype(int))]
    pts = np.vstack([np.zeros((1, 3))] + [drawing.frame(k)[0] for k in frames])
    lo, hi = pts.min(axis=0), pts.max(axis=0)
    centre, half = (lo + hi) / 2, max((hi - lo).max() / 2, 1e-9) * 1.05
    return centre - half, centre + half, hi - lo


def _shade(points, triangles, colors):
    a, b, c = (points[triangles[:, i]] for i in range(3))
    n = np.cross(b - a, c - a)
    n /= np.maximum(np.linalg.norm(n, axis=1, keepdims=True), 1e-300)
    light = 0.45 + 0.55 * np.abs(n @ LIGHT)
    return np.clip(colors * light[:, None], 0, 1)


def _view(drawing, frames, figsize=(6.4, 5.2)):
    fig = plt.figure(figsize=figsize)  # a fixed layout: constrained layout would redraw every frame thrice
    fig.subplots_adjust(left=0.02, right=0.95, bottom=0.05, top=0.95)
    ax = fig.add_subplot(projection="3d")
    lo, hi, extent = _bounds(drawing, frames)
    ax.set(xlim=(lo[0], hi[0]), ylim=(lo[1], hi[1]), zlim=(lo[2], hi[2]), xlabel="x [m]", ylabel="y [m]",
           zlabel="z [m]")
    ax.set_box_aspect((1, 1, 1))
    ax.view_init(*_camera(drawing.up, extent), vertical_axis=drawing.up)
    ax.set_title(drawing.result.model, fontsize=9)
    return fig, ax


# Azimuth that looks along a world axis, for each vertical axis.
LOOK_ALONG = {("y", "z"): 0, ("y", "x"): 90, ("z", "y"): -90, ("z", "x"): 0, ("x", "y"): 0, ("x", "z"): 90}


def _camera(up, extent):
    """(elevation, azimuth): a planar motion is seen nearly face on (from
    above when its plane is across "up"), anything else obliquely."""
    thin = int(np.argmin(extent))
    if extent[thin] >= 0.1 * extent.max():
        return 20, -60
    if "xyz"[thin] == up:
        return 65, -60
    return 15, LOOK_ALONG[(up, "xyz"[thin])] - 25


def _draw(ax, drawing, k, collection=None):
    points, triangles, _, cells = drawing.frame(k)
    faces = points[triangles]
    shades = _shade(points, triangles, cells["color"])
    if collection is None:
        collection = Poly3DCollection(faces, facecolors=shades, edgecolors="none")
        ax.add_collection3d(collection)
    else:
        collection.set_verts(faces)
        collection.set_facecolor(shades)
    return collection


def render_png(drawing, path, k=-1):
    """One frame (default the last) as a PNG."""
    k = k % len(drawing.result.time)
    fig, ax = _view(drawing, range(len(drawing.result.time)))
    _draw(ax, drawing, k)
    ax.text2D(0.02, 0.02, f"t = {drawing.result.time[k]:.4g} s", transform=ax.transAxes)
    fig.savefig(path, dpi=110)
    plt.close(fig)


def render_animation(drawing, path, frames=120, fps=25):
    """A GIF (.gif, Pillow) or MP4 (.mp4, ffmpeg on the PATH) over the run."""
    path = pathlib.Path(path)
    n = len(drawing.result.time)
    picks = np.unique(np.linspace(0, n - 1, min(frames, n)).round().astype(int))
    fig, ax = _view(drawing, picks)
    collection = _draw(ax, drawing, picks[0])
    label = ax.text2D(0.02, 0.02, "", transform=ax.transAxes)

    def update(k):
        _draw(ax, drawing, k, collection)
        label.set_text(f"t = {drawing.result.time[k]:.4g} s")
        return collection, label

    movie = animation.FuncAnimation(fig, update, frames=picks, blit=False)
    if path.suffix.lower() == ".mp4":
        if not shutil.which("ffmpeg"):
            raise RuntimeError("an .mp4 needs ffmpeg on the PATH; write a .gif instead")
        writer = animation.FFMpegWriter(fps=fps)
    elif path.suffix.lower() == ".gif":
        writer = animation.PillowWriter(fps=fps)
    else:
        raise ValueError(f"{path}: expected a .gif or .mp4 file name")
    movie.save(path, writer=writer, dpi=80)
    plt.close(fig)
