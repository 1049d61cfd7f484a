"""Cameras and lights between a DCC (Blender, Houdini) and volstyle, in pure Python.

volstyle's camera (SPEC §1, core/scene/camera.cpp) is a pinhole: eye, target, up, vertical field
of view, square pixels, width × height, optional near/far. A DCC camera is a 4×4 camera-to-world
matrix (looking down its local −Z, up its local +Y, as Blender and Houdini do), a lens and sensor,
a resolution and a pixel aspect. `to_volstyle` is a 4×4 matrix from the DCC's world into the
volume's own space (volstyle's world): for a Volume object that is the inverse of its world
matrix, so the camera sees the volume as the DCC shows it wherever the object sits.

volstyle's world is y-up. A volume made by volstyle shows upright in a z-up DCC when its object is
turned by BLENDER_FROM_VOLSTYLE, (x, y, z) → (x, −z, y), +90° about X (docs/LIGHTING.md)."""
from __future__ import annotations

import math
from typing import Sequence

Matrix = Sequence[Sequence[float]]  # 4×4, rows; column vectors (Blender's and mathutils' layout)
Vec = Sequence[float]

BLENDER_FROM_VOLSTYLE: list[list[float]] = [[1, 0, 0, 0], [0, 0, -1, 0], [0, 1, 0, 0], [0, 0, 0, 1]]
IDENTITY: list[list[float]] = [[1.0 if i == j else 0.0 for j in range(4)] for i in range(4)]


def transform_point(m: Matrix, p: Vec) -> list[float]:
    w = m[3][0] * p[0] + m[3][1] * p[1] + m[3][2] * p[2] + m[3][3]
    return [(m[i][0] * p[0] + m[i][1] * p[1] + m[i][2] * p[2] + m[i][3]) / w for i in range(3)]


def transform_direction(m: Matrix, d: Vec) -> list[float]:
    return [m[i][0] * d[0] + m[i][1] * d[1] + m[i][2] * d[2] for i in range(3)]


def multiply(a: Matrix, b: Matrix) -> list[list[float]]:
    return [[sum(a[i][k] * b[k][j] for k in range(4)) for j in range(4)] for i in range(4)]


def invert(m: Matrix) -> list[list[float]]:
    """The inverse of a 4×4 matrix (Gauss-Jordan with partial pivoting)."""
    a = [list(map(float, row)) + [1.0 if i == j else 0.0 for j in range(4)] for i, row in enumerate(m)]
    for c in range(4):
        p = max(range(c, 4), key=lambda r: abs(a[r][c]))
        if abs(a[p][c]) < 1e-300:
            raise ValueError("the matrix is singular")
        a[c], a[p] = a[p], a[c]
        pivot = a[c][c]
        a[c] = [x / pivot for x in a[c]]
        for r in range(4):
            if r != c and a[r][c] != 0.0:
                f = a[r][c]
                a[r] = [x - f * y for x, y in zip(a[r], a[c])]
    return [row[4:] for row in a]


def _norm(v: Vec) -> list[float]:
    n = math.sqrt(sum(x * x for x in v))
    if n == 0:
        raise ValueError("a zero vector")
    return [x / n for x in v]


def _dot(a: Vec, b: Vec) -> float:
    return sum(x * y for x, y in zip(a, b))


def _cross(a: Vec, b: Vec) -> list[float]:
    return [a[1] * b[2] - a[2] * b[1], a[2] * b[0] - a[0] * b[2], a[0] * b[1] - a[1] * b[0]]


def field_of_view_y(lens_mm: float, sensor_width_mm: float, sensor_height_mm: float, sensor_fit: str,
                    aspect_x: float, aspect_y: float) -> float:
    """The vertical field of view (degrees) of a lens on a sensor, as Blender fits the sensor to
    the frame: AUTO lays sensor_width along the frame's longer side, HORIZONTAL along its width,
    VERTICAL lays sensor_height along its height. `aspect_x/aspect_y` is the frame's displayed
    aspect (resolution × pixel aspect)."""
    fit = sensor_fit.upper()
    if fit == "AUTO":
        fit, sensor = ("HORIZONTAL" if aspect_x >= aspect_y else "VERTICAL"), sensor_width_mm
    else:
        sensor = sensor_width_mm if fit == "HORIZONTAL" else sensor_height_mm
    half = sensor / (2.0 * lens_mm)
    tan_half_y = half * aspect_y / aspect_x if fit == "HORIZONTAL" else half
    return math.degrees(2.0 * math.atan(tan_half_y))


def camera_from_dcc(matrix_world: Matrix, *, lens_mm: float, sensor_width_mm: float = 36.0, sensor_height_mm: float = 24.0,
                    sensor_fit: str = "AUTO", resolution: tuple[int, int] = (1920, 1080), percentage: float = 100.0,
                    pixel_aspect: tuple[float, float] = (1.0, 1.0), shift: tuple[float, float] = (0.0, 0.0),
                    clip: tuple[float, float] | None = None, to_volstyle: Matrix = IDENTITY, perspective: bool = True) -> dict:
    """A volstyle camera (the API's JSON) seeing what the DCC camera sees.

    Non-square pixels become square ones at the same displayed aspect (the height is scaled by
    pixel_aspect y/x). A lens shift or an orthographic camera has no volstyle equivalent and is
    refused (ValueError), as is a frame over 8192 pixels a side."""
    if not perspective:
        raise ValueError("an orthographic camera has no volstyle equivalent: use a perspective camera")
    if abs(shift[0]) > 1e-9 or abs(shift[1]) > 1e-9:
        raise ValueError(f"lens shift ({shift[0]:g}, {shift[1]:g}) has no volstyle equivalent: set shift to 0")
    if lens_mm <= 0:
        raise ValueError("the lens must be over 0 mm")
    width = max(1, round(resolution[0] * percentage / 100.0))
    height = max(1, round(resolution[1] * percentage / 100.0 * pixel_aspect[1] / pixel_aspect[0]))
    if width > 8192 or height > 8192:
        raise ValueError(f"{width}x{height}: volstyle renders at most 8192 pixels a side (lower the resolution %)")
    fov = field_of_view_y(lens_mm, sensor_width_mm, sensor_height_mm, sensor_fit, width, height)
    m = multiply(to_volstyle, matrix_world)
    eye = transform_point(m, (0.0, 0.0, 0.0))
    forward = _norm(transform_direction(m, (0.0, 0.0, -1.0)))
    up = _norm(transform_direction(m, (0.0, 1.0, 0.0)))
    camera = {"eye": eye, "target": [e + f for e, f in zip(eye, forward)], "up": up, "fov_y_deg": fov, "width": width, "height": height}
    if clip:
        scale = math.sqrt(sum(x * x for x in transform_direction(m, (0.0, 0.0, 1.0))))  # world units per camera unit
        camera["near"], camera["far"] = clip[0] * scale, clip[1] * scale
    return camera


def project(camera: dict, point: Vec) -> tuple[float, float] | None:
    """Where a volstyle camera sees a point: continuous pixel coordinates from the image's top-left
    corner (pixel centres at +0.5), as core/scene/camera.cpp projects; None behind the eye."""
    eye, target = camera["eye"], camera["target"]
    forward = _norm([t - e for t, e in zip(target, eye)])
    right = _norm(_cross(forward, camera.get("up", (0, 1, 0))))
    up = _cross(right, forward)
    rel = [p - e for p, e in zip(point, eye)]
    z = _dot(rel, forward)
    if z <= 0:
        return None
    w, h = camera["width"], camera["height"]
    tan_half = math.tan(math.radians(camera.get("fov_y_deg", 38.0)) / 2)
    x = _dot(rel, right) / (z * tan_half * w / h)
    y = _dot(rel, up) / (z * tan_half)
    return (x + 1) / 2 * w, (1 - y) / 2 * h


def sun_from_dcc(matrix_world: Matrix, strength: float, color: Vec = (1.0, 1.0, 1.0), to_volstyle: Matrix = IDENTITY) -> dict:
    """A volstyle directional light ({direction toward the light, irradiance}) from a sun lamp
    shining down its local −Z with `strength` W/m² (Blender's Sun strength is irradiance)."""
    m = multiply(to_volstyle, matrix_world)
    toward = _norm(transform_direction(m, (0.0, 0.0, 1.0)))
    return {"direction": toward, "irradiance": [strength * c for c in color[:3]]}


def camera_from_houdini(world_transform: Matrix, *, focal: float, aperture: float, resx: int, resy: int, aspect: float = 1.0,
                        win: tuple[float, float] = (0.0, 0.0), clip: tuple[float, float] | None = None, perspective: bool = True,
                        to_volstyle: Matrix = IDENTITY) -> dict:
    """A volstyle camera from a Houdini camera's parameters: `world_transform` as hou.Matrix4's
    rows (Houdini multiplies row vectors, p·M: transposed here), focal length and horizontal
    aperture in the same unit, resolution, pixel aspect, screen window offset (a lens shift:
    refused). Houdini's world is y-up like volstyle's and it places voxels as OpenVDB does, so a
    VDB from Houdini needs no other change."""
    column = [[float(world_transform[j][i]) for j in range(4)] for i in range(4)]
    return camera_from_dcc(column, lens_mm=focal, sensor_width_mm=aperture, sensor_height_mm=aperture, sensor_fit="HORIZONTAL",
                           resolution=(resx, resy), pixel_aspect=(aspect, 1.0), shift=win, clip=clip, to_volstyle=to_volstyle,
                           perspective=perspective)
