"""Top-down drawing of the AmigoBot on its path, to scale (pygame, imported only when used).

The whole path plus a margin of ``termination_distance + 0.25 m`` fits the square frame (x right, y up). Drawn: the
body (``body_length`` x ``body_width``, centred on A), the wheels (``2 r1`` long at K and L, with a spoke that turns
with the wheel angle), the castor (radius ``r3``, ``l5`` behind A), H (red) and its trail (green), the path (blue)
and a 0.5 m grid. ``"rgb_array"`` returns ``(H, W, 3)`` uint8; ``"human"`` shows a window at ``1/dt`` frames per
second. Both work headless with ``SDL_VIDEODRIVER=dummy``."""

from __future__ import annotations

import math
import os
from collections.abc import Sequence
from typing import TYPE_CHECKING, Any

import numpy as np
from numpy.typing import ArrayLike, NDArray

from amigo_gym.model.kinematics import castor_position, contact_points, h_position
from amigo_gym.paths.clothoid import PathSpec

if TYPE_CHECKING:
    from amigo_gym.task.v1 import TrackingParams


BACKGROUND = (255, 255, 255)
GRID = (228, 228, 228)
PATH = (40, 90, 200)
TRAIL = (30, 160, 60)
BODY = (200, 200, 205)
BODY_EDGE = (70, 70, 80)
WHEEL = (30, 30, 30)
SPOKE = (230, 230, 230)
CASTOR = (90, 90, 90)
POINT_H = (220, 30, 30)
POINT_A = (0, 0, 0)
TEXT = (20, 20, 20)


def path_polyline(path: PathSpec, n: int = 400) -> NDArray[np.float64]:
    """Points along one traversal of the path (closed for a circle), ``(n + 1, 2)`` [m]."""
    s = np.linspace(0.0, path.length, n + 1, dtype=np.float64)
    q = path.pose_columns(s)
    return np.stack((np.broadcast_to(q.x, s.shape), np.broadcast_to(q.y, s.shape)), axis=-1).astype(np.float64)


def _rotated_rect(cx: float, cy: float, heading: float, length: float, width: float) -> NDArray[np.float64]:
    """Corners ``(4, 2)`` [m] of a ``length`` x ``width`` rectangle centred at (cx, cy), long side along heading."""
    c, s = math.cos(heading), math.sin(heading)
    hl, hw = 0.5 * length, 0.5 * width
    local = np.array([[hl, hw], [hl, -hw], [-hl, -hw], [-hl, hw]])
    corners: NDArray[np.float64] = np.array([cx, cy]) + local @ np.array([[c, s], [-s, c]])
    return corners


class Renderer:
    """Draws frames of one robot on ``path`` (one per environment; holds the window in ``"human"`` mode), ``size``
    pixels square."""

    def __init__(self, params: TrackingParams, path: PathSpec, mode: str = "rgb_array", size: int = 600) -> None:
        if mode not in ("rgb_array", "human"):
            raise ValueError(f"render mode must be 'rgb_array' or 'human', got {mode!r}")
        try:
            import pygame
        except ImportError as exc:  # pragma: no cover
            from gymnasium.error import DependencyNotInstalled

            raise DependencyNotInstalled(
                'rendering needs pygame: pip install "amigo-gym[render]" (from a clone: pip install -e ".[render]")'
            ) from exc
        self._pg: Any = pygame
        self.params, self.path, self.mode, self.size = params, path, mode, int(size)
        pts = path_polyline(path)  # the view: a square around the path with a margin
        lo, hi = pts.min(axis=0), pts.max(axis=0)
        half = 0.5 * float(np.max(hi - lo)) + (params.termination_distance + 0.25)
        cx, cy = (float(c) for c in 0.5 * (lo + hi))
        self._origin = (cx - half, cy - half)
        self.scale = self.size / ((cx + half) - (cx - half))  # px per metre
        self._path_px = [self._px(p) for p in pts]
        self._window: Any = None
        self._clock: Any = None
        if mode == "human":
            pygame.display.init()
            pygame.display.set_caption("AmigoBot")
            self._window = pygame.display.set_mode((self.size, self.size))
            self._clock = pygame.time.Clock()
        try:
            pygame.font.init()
            self._font: Any = pygame.font.Font(None, 20)
        except Exception:  # fonts are optional
            self._font = None
        self._background = self._draw_background()

    def _px(self, p: ArrayLike) -> tuple[float, float]:
        q = np.asarray(p, dtype=np.float64)
        return ((q[0] - self._origin[0]) * self.scale, self.size - (q[1] - self._origin[1]) * self.scale)

    def _draw_background(self) -> Any:
        pg = self._pg
        surf = pg.Surface((self.size, self.size))
        surf.fill(BACKGROUND)
        x0, y0 = self._origin
        span, step = self.size / self.scale, 0.5
        for k in range(math.ceil(x0 / step), math.floor((x0 + span) / step) + 1):
            x, _ = self._px((k * step, 0.0))
            pg.draw.line(surf, GRID, (x, 0), (x, self.size))
        for k in range(math.ceil(y0 / step), math.floor((y0 + span) / step) + 1):
            _, y = self._px((0.0, k * step))
            pg.draw.line(surf, GRID, (0, y), (self.size, y))
        pg.draw.aalines(surf, PATH, False, self._path_px)
        return surf

    def _polygon(self, surf: Any, corners: NDArray[np.float64], fill: tuple[int, int, int], edge: Any) -> None:
        from pygame import gfxdraw

        ipts = [(round(x), round(y)) for x, y in map(self._px, corners)]
        gfxdraw.filled_polygon(surf, ipts, fill)
        gfxdraw.aapolygon(surf, ipts, edge)

    def draw(
        self,
        pose: ArrayLike,
        trail: Sequence[Sequence[float]] = (),
        *,
        wheel_angles: ArrayLike | None = None,
        time: float | None = None,
        cross_track_error: float | None = None,
    ) -> NDArray[np.uint8] | None:
        """Draw the robot at ``pose`` ``(x_A [m], y_A [m], beta [rad])`` with H's ``trail`` (``(x, y)`` [m], oldest
        first), the ``wheel_angles`` [rad], and the ``time`` [s] and ``cross_track_error`` [m] printed when given;
        the frame ``(size, size, 3)`` uint8 in ``rgb_array`` mode, ``None`` in ``human`` mode."""
        pg = self._pg
        robot = self.params.robot
        pose = np.asarray(pose, dtype=np.float64)
        x, y, b = float(pose[0]), float(pose[1]), float(pose[2])
        surf = self._background.copy()
        if len(trail) >= 2:
            pg.draw.aalines(surf, TRAIL, False, [self._px(p) for p in trail])
        body = _rotated_rect(x, y, b, robot.body_length, robot.body_width)
        self._polygon(surf, body, BODY, BODY_EDGE)
        k, l_ = contact_points(pose, robot)
        alphas = (0.0, 0.0) if wheel_angles is None else tuple(np.asarray(wheel_angles, dtype=np.float64)[:2])
        for c, r, alpha in ((k, robot.r1, alphas[0]), (l_, robot.r2, alphas[1])):
            self._polygon(surf, _rotated_rect(float(c[0]), float(c[1]), b, 2 * r, 0.025), WHEEL, WHEEL)
            # spoke: the wheel's visible rotation, projected on the ground (length r cos(alpha))
            tip = np.asarray(c) + r * math.cos(alpha) * np.array([math.cos(b), math.sin(b)])
            pg.draw.line(surf, SPOKE, self._px(c), self._px(tip), 2)
        cpx = self._px(castor_position(pose, robot))
        pg.draw.circle(surf, CASTOR, cpx, max(2.0, robot.r3 * self.scale))
        front = (x + 0.5 * robot.body_length * math.cos(b), y + 0.5 * robot.body_length * math.sin(b))
        pg.draw.line(surf, BODY_EDGE, self._px((x, y)), self._px(front), 2)
        pg.draw.circle(surf, POINT_A, self._px((x, y)), 3)
        pg.draw.circle(surf, POINT_H, self._px(h_position(pose, robot)), 4)
        parts = [] if time is None else [f"t = {time:6.2f} s"]
        parts += [] if cross_track_error is None else [f"e = {1000 * cross_track_error:+7.1f} mm"]
        if self._font is not None and parts:
            surf.blit(self._font.render("   ".join(parts), True, TEXT), (8, 8))
        if self.mode == "human":
            assert self._window is not None
            self._window.blit(surf, (0, 0))
            pg.event.pump()
            pg.display.flip()
            self._clock.tick(1.0 / self.params.dt)
            return None
        return np.ascontiguousarray(np.transpose(pg.surfarray.array3d(surf), (1, 0, 2)), dtype=np.uint8)

    def close(self) -> None:
        """Close the window (human mode)."""
        if self._window is not None:
            self._pg.display.quit()
            self._window = None


def headless() -> None:
    """Select SDL's dummy video driver when no display is available (tests, servers)."""
    os.environ.setdefault("SDL_VIDEODRIVER", "dummy")
