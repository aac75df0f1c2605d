r"""An animation of the moving body, streamed from a run directory (private).

For ``N = 3`` (Section 4, Appendix 2): the fixed point at the origin, the body axis of the Lagrange top from the
fixed point to its centre of mass ``z`` (on the sphere ``|z| = const``), the material point ``x − z`` joined to
the fixed point by a thin dashed line, and a fading trail of both points.  For other ``N`` the same with ``y_0``
(material point's place) and ``y_{N−1}`` (on its sphere).  All quantities are dimensionless.

Frame ``j`` shows saved row ``j·stride``; rows are read from HDF5 in slices of at most 256 frames, so a run of
any length is animated in constant memory for the rows (a GIF keeps its frames, one byte per pixel, until it is
written; an MP4 is piped to ffmpeg frame by frame).
"""

from __future__ import annotations

import math
from collections import deque
from enum import StrEnum
from pathlib import Path
from typing import Any

import numpy as np
from matplotlib.backends.backend_agg import FigureCanvasAgg
from matplotlib.colors import to_rgba

from .._errors import InvalidParameterError, RecordingError
from ._files import run_title
from ._orbit import AXIS_LABELS, POINT_COLORS, new_figure, point_sets, sphere_label
from ._runs import open_run

__all__ = ["AnimationFormat", "animate_run", "frame_rows"]

_SLICE_FRAMES = 256


class AnimationFormat(StrEnum):
    """Animation file format, from the suffix of the output file."""

    gif = "gif"
    mp4 = "mp4"


#: most frames of one animation (a GIF keeps every frame in memory, ~0.4 MB each at the default size: ~4 GB)
MAX_FRAMES = 10_000


def frame_rows(rows: int, frames: int, stride: int | None) -> tuple[int, int]:
    """``(stride, count)``: frame ``j`` shows saved row ``j·stride``.  The default stride spreads ``frames``
    frames over the run, ``max(1, floor((rows − 1) / (frames − 1)))``; ``count = min(frames, ceil(rows / stride))``.
    ``frames`` is at most :data:`MAX_FRAMES`."""
    if isinstance(frames, bool) or not isinstance(frames, int | np.integer) or not 2 <= frames <= MAX_FRAMES:
        raise InvalidParameterError(f"frames must be an integer between 2 and {MAX_FRAMES}, got {frames!r}")
    if stride is None:
        stride = max(1, (rows - 1) // (frames - 1))
    if stride < 1:
        raise InvalidParameterError(f"stride must be >= 1, got {stride}")
    return stride, min(frames, math.ceil(rows / stride))


def _frame_slices(run, stride, count):
    """Yield the frame rows' states in slices of at most ``_SLICE_FRAMES`` frames."""
    for j0 in range(0, count, _SLICE_FRAMES):
        j1 = min(count, j0 + _SLICE_FRAMES)
        idx, X = run.read(j0 * stride, (j1 - 1) * stride + 1, stride)
        yield idx, X


def _ffmpeg_path() -> str:
    try:
        import imageio_ffmpeg
    except ImportError:
        raise InvalidParameterError(
            "an .mp4 animation needs imageio-ffmpeg: pip install 'jetgaudin[animation]' (or write a .gif)"
        ) from None
    return imageio_ffmpeg.get_ffmpeg_exe()


class _GifSink:
    """Collect palette frames (one byte per pixel) and write an animated GIF with Pillow."""

    def __init__(self, path: Path, fps: float):
        self.path, self.duration = path, max(20, round(1000 / fps))
        self.frames: list[Any] = []

    def add(self, rgba: np.ndarray) -> None:
        from PIL import Image

        self.frames.append(Image.fromarray(rgba[..., :3]).quantize(colors=128, dither=Image.Dither.NONE))

    def close(self) -> None:
        self.frames[0].save(
            self.path, save_all=True, append_images=self.frames[1:], duration=self.duration, loop=0, optimize=False
        )


class _Mp4Sink:
    """Pipe RGB frames to ffmpeg (libx264, yuv420p) as they are drawn."""

    def __init__(self, path: Path, fps: float, size: tuple[int, int]):
        import subprocess

        w, h = size
        cmd = [
            _ffmpeg_path(),
            "-y",
            "-loglevel",
            "error",
            "-f",
            "rawvideo",
            "-pix_fmt",
            "rgb24",
            "-s",
            f"{w}x{h}",
            "-r",
            f"{fps:g}",
            "-i",
            "-",
            "-an",
            "-vf",
            "pad=ceil(iw/2)*2:ceil(ih/2)*2",
            "-vcodec",
            "libx264",
            "-pix_fmt",
            "yuv420p",
            str(path),
        ]
        self.proc = subprocess.Popen(cmd, stdin=subprocess.PIPE)
        assert self.proc.stdin is not None
        self.stdin = self.proc.stdin

    def add(self, rgba: np.ndarray) -> None:
        self.stdin.write(np.ascontiguousarray(rgba[..., :3]).tobytes())

    def close(self) -> None:
        self.stdin.close()
        if self.proc.wait() != 0:
            raise RecordingError("ffmpeg failed to write the .mp4 animation")


def _chain_sets(model):
    """``(sets_of, colours)`` of a chain run: the ``y_0`` of each site (at most :data:`MAX_SITES`), one colour each
    (for a magnet, the spins)."""
    from matplotlib import colormaps

    from ._chains import MAX_SITES, site_y0

    S = min(len(model.sites), MAX_SITES)

    def sets_of(X):
        Y = site_y0(model, X)
        return [(f"y_0 of site {i + 1} (λ = {p:g}, N = {N})", Y[:, i]) for i, (p, N) in enumerate(model.sites[:S])]

    return sets_of, tuple(colormaps["tab10"](i) for i in range(S))


def animate_run(
    run_dir,
    out,
    *,
    orbit: int | None = None,
    frames: int = 100,
    fps: float = 20.0,
    stride: int | None = None,
    trail: int = 30,
    dpi: int = 100,
) -> Path:
    """Write an animation (``.gif`` or ``.mp4``) of the body moving along a run's saved rows.

    Parameters
    ----------
    run_dir : path
        An orbit, ensemble or flow run directory (finished or interrupted: only the safe rows are used).
    out : path
        Output file; its suffix (``.gif`` or ``.mp4``) selects the format.
    orbit : int, optional
        The orbit of an ensemble run (default 0).
    frames : int
        Largest number of frames (at least 2).
    fps : float
        Frames per second.
    stride : int, optional
        Saved rows between frames (default: the frames spread over the whole run).
    trail : int
        Number of past frames in the fading trail.
    dpi : int
        Resolution (the figure is 6 × 6.4 inches).

    Returns
    -------
    Path

    Raises
    ------
    InvalidParameterError
        Unknown suffix, bad counts, ``.mp4`` without imageio-ffmpeg.
    RecordingError
        Not a run directory, no safe rows.
    """
    out = Path(out)
    try:
        fmt = AnimationFormat(out.suffix.lower().lstrip("."))
    except ValueError:
        raise InvalidParameterError(f"the animation file must end in .gif or .mp4, got {out.name!r}") from None
    if not (0 < fps <= 100) or not math.isfinite(fps):
        raise InvalidParameterError(f"fps must be in (0, 100], got {fps}")
    if trail < 0:
        raise InvalidParameterError(f"trail must be >= 0, got {trail}")
    if not 20 <= dpi <= 600:
        raise InvalidParameterError(f"dpi must be between 20 and 600, got {dpi}")
    if fmt is AnimationFormat.mp4:
        _ffmpeg_path()
    run = open_run(run_dir, orbit=orbit)
    if run.rows == 0:
        raise RecordingError(f"{run_dir}: no saved row is declared safe in run.json yet; nothing to animate")
    stride, count = frame_rows(run.rows, frames, stride)
    N = run.N
    model = run.model()  # a chain: each site's y_0 moves (no body, no invariant sphere common to the sites)
    sets_of, colors = (point_sets, POINT_COLORS) if model is None else _chain_sets(model)
    # pass 1 over the frame rows only: the bounds of the picture
    lo, hi = np.full(3, np.inf), np.full(3, -np.inf)
    r = -1.0 if model is None else 0.0
    for _, X in _frame_slices(run, stride, count):
        if r < 0:
            r = float(np.linalg.norm(X[0, 3 * N - 3 :]))
        for _, P in sets_of(X):
            lo, hi = np.minimum(lo, P.min(axis=0)), np.maximum(hi, P.max(axis=0))
    lo, hi = np.minimum(lo, -r), np.maximum(hi, r)
    mid, half = (lo + hi) / 2, max(float((hi - lo).max()) / 2, 1e-12) * 1.05

    fig = new_figure(figsize=(6, 6.4), dpi=dpi)
    ax = fig.add_subplot(projection="3d", computed_zorder=False)
    ax.set_xlim(mid[0] - half, mid[0] + half)
    ax.set_ylim(mid[1] - half, mid[1] + half)
    ax.set_zlim(mid[2] - half, mid[2] + half)
    ax.set_box_aspect((1, 1, 1))
    for setter, lab in zip((ax.set_xlabel, ax.set_ylabel, ax.set_zlabel), AXIS_LABELS, strict=True):
        setter(lab.replace(" (dimensionless)", ""), fontsize=8)
    ax.tick_params(labelsize=7)
    u, v = np.meshgrid(np.linspace(0, 2 * np.pi, 25), np.linspace(0, np.pi, 13))
    ax.plot_wireframe(
        r * np.cos(u) * np.sin(v),
        r * np.sin(u) * np.sin(v),
        r * np.cos(v),
        color="0.55",
        linewidth=0.4,
        alpha=0.45 if model is None else 0.0,
        zorder=0,
        label=sphere_label(N, r) if model is None else None,
    )
    ax.scatter([0], [0], [0], s=30, color="black", marker="o", zorder=5,
               label="fixed point (origin)" if model is None else "origin")
    labels = [lab for lab, _ in sets_of(np.zeros((1, 3 * N)))]
    from mpl_toolkits.mplot3d.art3d import Line3DCollection

    trails = [Line3DCollection([], linewidths=1.4, zorder=1) for _ in labels]
    for t in trails:
        ax.add_collection3d(t, autolim=False)
    heads = [
        ax.plot([], [], [], "o", color=c, markersize=7, zorder=4, label=lab)[0]
        for lab, c in zip(labels, colors, strict=False)
    ]
    axis_label = "body axis: fixed point → centre of mass" if N == 3 else f"axis: origin → y_{N - 1}"
    axis_label = axis_label if model is None else "origin → y_0 of site 1"
    (axis_line,) = ax.plot([], [], [], "-", color="black", linewidth=2.5, zorder=3, label=axis_label)
    (mp_line,) = ax.plot([], [], [], "--", color=POINT_COLORS[0], linewidth=0.8, zorder=2)
    fig.legend(loc="lower center", ncol=2, fontsize=7, frameon=False)
    fig.suptitle(run_title(run), fontsize=7, wrap=True)
    step_text = fig.text(0.02, 0.9, "", fontsize=8, family="monospace")
    fig.subplots_adjust(left=0.02, right=0.98, bottom=0.1, top=0.88)

    path = out
    canvas = fig.canvas
    assert isinstance(canvas, FigureCanvasAgg)
    sink: _GifSink | _Mp4Sink | None = None
    hist: list[deque[np.ndarray]] = [deque(maxlen=trail + 1) for _ in labels]
    try:
        for idx, X in _frame_slices(run, stride, count):
            for i_row, x in zip(idx, X, strict=True):
                sets = sets_of(x[None, :])
                for (_, P), head, h, tr, c in zip(sets, heads, hist, trails, colors, strict=False):
                    p = P[0]
                    h.append(p)
                    head.set_data_3d([p[0]], [p[1]], [p[2]])
                    pts = np.array(h)
                    segs = np.stack([pts[:-1], pts[1:]], axis=1) if len(pts) > 1 else np.zeros((0, 2, 3))
                    tr.set_segments(segs)
                    rgba = np.tile(np.array(to_rgba(c)), (len(segs), 1))
                    rgba[:, 3] = np.linspace(0.05, 0.9, len(segs)) if len(segs) else rgba[:, 3]
                    tr.set_color(rgba)
                # the top: the axis to the last point set and the dashed line to the first (x − z); a chain: only
                # the line from the origin to site 1's y_0
                a = sets[-1][1][0] if model is None else sets[0][1][0]
                axis_line.set_data_3d([0, a[0]], [0, a[1]], [0, a[2]])
                if model is None:
                    m = sets[0][1][0]
                    mp_line.set_data_3d([0, m[0]], [0, m[1]], [0, m[2]])
                label = "t" if run.index_name == "t" else "n"
                step_text.set_text(f"{label} = {i_row:g}" if label == "t" else f"step n = {int(i_row)}")
                canvas.draw()
                rgba_img = np.asarray(canvas.buffer_rgba())
                if sink is None:
                    h_px, w_px = rgba_img.shape[:2]
                    sink = _GifSink(path, fps) if fmt is AnimationFormat.gif else _Mp4Sink(path, fps, (w_px, h_px))
                sink.add(rgba_img)
        assert sink is not None  # count >= 1 frame was drawn
        sink.close()
    except BaseException:
        if isinstance(sink, _Mp4Sink):  # do not leave ffmpeg waiting on its pipe
            sink.proc.kill()
            sink.proc.wait()
        raise
    return path
