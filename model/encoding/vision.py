"""Vision encoding (paper 4.1.1, Fig. 7): one camera frame -> shape, colour and position features.

The pipeline, per frame (RGB uint8, any size):

1. **Downscale** to ``VisionParams.work_width`` pixels wide (160 by default, aspect kept). Mean
   shift is the expensive step (at 320x240 ``pyrMeanShiftFiltering`` costs ~83 ms with
   ``maxLevel=0`` and ~27 ms with ``maxLevel=1``); at 160x120 with ``maxLevel=1`` and a spatial
   radius of 4 it costs ~3 ms and the whole pipeline ~6 ms of CPU per 320x240 rendered frame
   (``benchmarks/vision.py``). The contour is refined at full resolution (step 5).
2. **Mean-shift segmentation** (Comaniciu & Meer 2002): ``cv2.pyrMeanShiftFiltering``.
3. **Object mask by colour saturation**. The largest contour is not the object: the robot's arm
   enters from the image border and merges with it. The object is the *most saturated sizeable
   region*, where a pixel's saturation is the smaller of its HSV saturation as seen and after
   white balancing the image against its own median colour (the table, which fills most of the
   view). A tinted table (wood, cloth, coloured light) is grey once balanced; a grey or white arm
   that balancing against a tinted table would colour is not saturated as seen. Pixels above
   ``max(min_saturation, saturation_fraction * p99.5(saturation))`` form the mask. A region
   touching the image border (the arm enters from there) has its mean saturation multiplied by
   ``border_penalty``; the chosen region needs a (penalised) mean saturation of at least
   ``min_saturation``, so a slightly tinted arm alone is not an object.
4. **Canny edges** of the mean-shifted image (colour Canny: the strongest gradient
   over R, G, B) cut regions that touch in the saturation mask (the object and a tinted arm).
   Touching pieces of the chosen piece's hue (``hue_tolerance``) and at least half its saturation
   are merged back, so the edges between an object's faces (a dice's lit and shaded sides, a
   phone's dark screen, an apple's shadowed half) do not cut it.
5. **Contour finder** (Suzuki & Abe 1985): ``cv2.findContours`` on the object mask, upsampled to
   the frame's full resolution (on the boundary band each pixel goes to the object or the
   background by which mean colour of the frame it is nearer, recovering the detail lost by
   downscaling); the largest external contour is the object's.
6. **Centre of mass** from the contour's moments and **16 salient distances**: for each 22.5
   degree sector around the centre of mass, the largest distance to a contour point in it (0 if
   the contour has no point in the sector, e.g. the far side of a crescent whose centre of mass
   lies outside it), scaled by the square root of the area, then rotated so that the largest comes
   first, continuing clockwise (image coordinates, y down). When several sectors are within 8 %
   of the largest (symmetric shapes: a rectangle's corners, a crescent's tips), the start is the
   one followed by the larger distances clockwise, so the order does not flip with pixel noise.
   The ratio d / sqrt(A) is about 0.56 for a disc, 0.71 at a square's corner and above 1 for
   long shapes, so it is squashed into [0, 1) with ``1 - exp(-d / sqrt(A))`` (monotone, no
   clipping, no tuning constant: disc 0.43, square corner 0.51, a 10:1 stick 0.79). Sectors are
   fixed in the image, so the 16 values are only approximately rotation invariant (a concave
   shape's gap can move by one sector).
7. **Mean R, G, B** of the frame's pixels inside the contour, in [0, 1]: the paper's raw mean
   (``white_balance="none"``, the default). ``white_balance="grey_world"`` divides them by the
   scene's white estimate (the per-channel median of the mean-shifted frame, normalised to keep
   brightness), which removes a colour cast of light or camera but assumes a grey table. On
   rendered recordings with tinted tables (wood, cloth) and +-14 % camera white balance, and
   under extra global casts, neither was better (colour classification within +-2 %), so the
   default stays with the paper.
8. **Centroid** (x / width, y / height) in [0, 1]: 2 optional extra values.

Output: ``np.ndarray[21]`` float32, the paper's 19 values (``VISUAL_FEATURES``) then the centroid.

No object found (no region saturated enough and large enough): :func:`extract_features` returns
all zeros (no real object has a zero largest distance, so ``features[0] == 0`` flags it);
:func:`encode_frames` replaces such frames by the features of the nearest earlier frame with an
object (or the nearest later one at the start of a recording); a recording without any object
stays all zeros. :func:`encode_frames_found` also returns which frames had an object.
"""

from __future__ import annotations

import logging
from concurrent.futures import ThreadPoolExecutor
from dataclasses import dataclass
from typing import Literal

import cv2
import numpy as np

logger = logging.getLogger(__name__)

SECTORS = 16  # one per 22.5 degrees
VISUAL_FEATURES = 19  # 16 distances + mean R, G, B: what the paper's MTRNN_v sees
FEATURES = VISUAL_FEATURES + 2  # + centroid x, y
MIN_SIDE = 16  # smallest frame side accepted, in pixels


@dataclass(frozen=True)
class VisionParams:
    """Parameters of the Fig. 7 pipeline. Defaults were tuned on synthetic and rendered frames."""

    work_width: int = 160  # frames are resized to this width (aspect kept) before mean shift
    spatial_radius: int = 4  # mean shift spatial window (pixels at working resolution; 6 costs 2x)
    colour_radius: int = 24  # mean shift colour window
    max_level: int = 1  # mean shift pyramid levels (0 is ~3x slower)
    canny_low: int = 40  # Canny hysteresis thresholds on the mean-shifted image (colour)
    canny_high: int = 100
    min_saturation: float = 0.22  # floor of the object's saturation threshold (HSV S in [0, 1])
    saturation_fraction: float = 0.5  # threshold relative to the 99.5th percentile saturation
    min_value: float = 0.12  # pixels darker than this (HSV V in [0, 1]) have unreliable hue
    hue_tolerance: float = 20.0  # degrees: touching pieces of the object's hue join it
    edge_regrow: int = 4  # pixels the object may grow back into edge pixels of its own colour
    min_area_fraction: float = 0.0015  # smallest object, as a fraction of the image
    max_area_fraction: float = 0.5  # larger saturated regions are a coloured table, not an object
    border_penalty: float = 0.5  # score factor for regions touching the image border (the arm)
    white_balance: Literal["none", "grey_world"] = "none"  # colour features; "none" = the paper

    def __post_init__(self) -> None:
        if self.white_balance not in ("none", "grey_world"):
            raise ValueError(f"white_balance must be 'none' or 'grey_world', got {self.white_balance!r}")
        if self.work_width < MIN_SIDE:
            raise ValueError(f"work_width must be at least {MIN_SIDE} pixels, got {self.work_width}")


@dataclass
class VisionSteps:
    """The intermediate images of one frame, all at the frame's size, for the teaching pages."""

    original: np.ndarray  # [H, W, 3] RGB uint8, the input
    mean_shift: np.ndarray  # [H, W, 3] RGB uint8, mean-shift segmentation (computed at work_width)
    saturation: np.ndarray  # [H, W] uint8, the saturation (0..255) the object is chosen by (step 3)
    edges: np.ndarray  # [H, W] uint8, Canny edges (255 on an edge)
    object_mask: np.ndarray  # [H, W] uint8, the chosen object's pixels (255)
    contour: np.ndarray  # [H, W, 3] RGB uint8, the original with the chosen contour drawn
    rays: np.ndarray  # [H, W, 3] RGB uint8, centre of mass and the 16 salient distances drawn
    features: np.ndarray  # [21] float32, as extract_features
    found: bool  # whether an object was found (if not, features are zeros)


@dataclass
class _Result:
    features: np.ndarray
    found: bool
    contour: np.ndarray | None = None  # [N, 1, 2] int32, full resolution
    centre: tuple[float, float] | None = None
    ray_points: np.ndarray | None = None  # [16, 2] salient contour points in sector order
    small_ms: np.ndarray | None = None
    small_sat: np.ndarray | None = None
    small_edges: np.ndarray | None = None
    mask: np.ndarray | None = None  # full-resolution object mask


def _check_frame(frame: np.ndarray) -> np.ndarray:
    if not isinstance(frame, np.ndarray):
        raise ValueError(f"frame must be a numpy array (H x W x 3 RGB uint8), got {type(frame).__name__}")
    if frame.dtype != np.uint8:
        if np.issubdtype(frame.dtype, np.floating) and np.isnan(frame).any():
            raise ValueError("frame contains NaN values; expected H x W x 3 RGB uint8 pixels")
        raise ValueError(
            f"frame must have dtype uint8 (0..255 RGB), got {frame.dtype}; "
            "convert e.g. with (frame * 255).round().astype(np.uint8) for floats in [0, 1]"
        )
    if frame.ndim != 3 or frame.shape[2] != 3:
        hint = " (RGBA? drop the alpha channel)" if frame.ndim == 3 and frame.shape[2] == 4 else ""
        raise ValueError(f"frame must have shape H x W x 3 (RGB), got {frame.shape}{hint}")
    if min(frame.shape[:2]) < MIN_SIDE:
        raise ValueError(
            f"frame is too small: {frame.shape[1]}x{frame.shape[0]}, need >= {MIN_SIDE} px a side"
        )
    return np.ascontiguousarray(frame)


def _white_gains(image: np.ndarray) -> np.ndarray:
    """Per-channel gains that map the image's median colour (the table) to grey of equal brightness."""
    ref = np.median(image.reshape(-1, 3)[::3], axis=0).astype(np.float64) + 1.0
    return np.clip(ref.mean() / ref, 0.33, 3.0)


def _hue_distance(a: np.ndarray, b: float) -> np.ndarray:
    """Circular distance in degrees."""
    d = np.abs(a - b) % 360.0
    return np.minimum(d, 360.0 - d)


def _select_object(small: np.ndarray, params: VisionParams, keep: bool) -> tuple[np.ndarray | None, dict]:
    """Steps 2-4: mean shift, saturation, Canny; returns the object's mask at working resolution."""
    ms, hsv, sat_eff, edges, gains = _saturation_and_edges(small, params)
    info: dict = {"ms": ms, "sat": sat_eff, "edges": edges, "gains": gains} if keep else {"gains": gains}

    high = float(np.percentile(sat_eff, 99.5))
    thr = max(params.min_saturation * 255.0, params.saturation_fraction * high)
    mask = (sat_eff >= thr).astype(np.uint8)
    if not mask.any():
        return None, info
    # Closing bridges the 1-2 px gaps Canny leaves at junctions (where the arm meets the object).
    closed = cv2.morphologyEx(edges, cv2.MORPH_CLOSE, np.ones((3, 3), np.uint8))
    pieces = mask & (closed == 0)
    n, labels, stats, _ = cv2.connectedComponentsWithStats(pieces, connectivity=4)
    flat = labels.ravel()
    count = np.bincount(flat, minlength=n).astype(np.float64)
    piece_sat = np.bincount(flat, sat_eff.ravel(), minlength=n) / np.maximum(count, 1) / 255.0
    best = _best_piece(stats, piece_sat, small.shape[:2], params)
    if best is None:
        return None, info
    obj = _merge_faces(ms, hsv, mask, closed, labels, count, piece_sat, best, params)
    return obj, info


def _saturation_and_edges(
    small: np.ndarray, params: VisionParams
) -> tuple[np.ndarray, np.ndarray, np.ndarray, np.ndarray, np.ndarray]:
    """Steps 2-3: the mean-shift image, its HSV, the effective saturation, Canny edges, white gains."""
    ms = cv2.pyrMeanShiftFiltering(
        small, params.spatial_radius, params.colour_radius, maxLevel=params.max_level
    )
    gains = _white_gains(ms)
    balanced = np.clip(ms.astype(np.float32) * gains.astype(np.float32), 0, 255).astype(np.uint8)
    hsv = cv2.cvtColor(ms, cv2.COLOR_RGB2HSV_FULL)  # hue 0..255 over 360 degrees
    balanced_sat = cv2.cvtColor(balanced, cv2.COLOR_RGB2HSV_FULL)[..., 1]
    # Saturated as seen AND relative to the table: a tinted table is neither (it is grey once
    # balanced), a grey arm that balancing against a tinted table colours is not saturated as seen.
    sat = np.minimum(hsv[..., 1], balanced_sat)
    bright = hsv[..., 2] >= params.min_value * 255
    sat_eff = np.where(bright, sat, 0).astype(np.uint8)
    # Colour Canny (the strongest gradient over R, G, B): an arm as bright as the object still
    # differs from it in some channel.
    edges = cv2.Canny(ms, params.canny_low, params.canny_high)
    return ms, hsv, sat_eff, edges, gains


def _best_piece(
    stats: np.ndarray, piece_sat: np.ndarray, shape: tuple[int, ...], params: VisionParams
) -> int | None:
    """Step 4, first half: the most saturated sizeable piece (penalised at the border), if saturated."""
    h, w = shape
    x, y, bw, bh, area = stats.T
    touches_border = (x == 0) | (y == 0) | (x + bw == w) | (y + bh == h)
    score = piece_sat * np.where(touches_border, params.border_penalty, 1.0)
    sizeable = (area >= params.min_area_fraction * h * w) & (area <= params.max_area_fraction * h * w)
    sizeable[0] = False  # label 0 is everything outside the mask
    score[~sizeable] = 0.0
    best = int(np.argmax(score))
    if score[best] < params.min_saturation:  # a (penalised) region must still be saturated
        return None
    return best


def _merge_faces(
    ms: np.ndarray,
    hsv: np.ndarray,
    mask: np.ndarray,
    closed: np.ndarray,
    labels: np.ndarray,
    count: np.ndarray,
    piece_sat: np.ndarray,
    best: int,
    params: VisionParams,
) -> np.ndarray:
    """Step 4, second half: faces of the object that edges cut off the chosen piece (a dice's lit and
    shaded sides, a phone's dark screen, an apple's shadowed half) touch it and share its hue;
    merge those, face by face, then give back the edge pixels of that hue."""
    n = len(count)
    flat = labels.ravel()
    mean_rgb = np.stack([np.bincount(flat, ms[..., c].ravel(), minlength=n) for c in range(3)], axis=1)
    mean_rgb /= np.maximum(count, 1)[:, None]
    piece_hue = cv2.cvtColor((mean_rgb / 255.0).astype(np.float32)[:, None, :], cv2.COLOR_RGB2HSV)[:, 0, 0]
    seed_hue, seed_sat = float(piece_hue[best]), float(piece_sat[best])
    joins = (_hue_distance(piece_hue, seed_hue) <= params.hue_tolerance) & (piece_sat >= 0.5 * seed_sat)
    joins &= count >= 4
    joins[0] = False
    in_obj = np.zeros(n, bool)
    in_obj[best] = True
    kernel = np.ones((3, 3), np.uint8)
    obj = (labels == best).astype(np.uint8)
    for _ in range(n):
        near = cv2.dilate(obj, kernel, iterations=2).astype(bool)
        touching = np.zeros(n, bool)
        touching[labels[near]] = True
        new = touching & joins & ~in_obj
        if not new.any():
            break
        in_obj |= new
        obj = in_obj[labels].astype(np.uint8)
    hue_deg = hsv[..., 0].astype(np.float32) * (360.0 / 256.0)
    zone = (mask.astype(bool) & (closed > 0) & (_hue_distance(hue_deg, seed_hue) <= params.hue_tolerance)) | (
        obj > 0
    )
    for _ in range(params.edge_regrow):
        obj = cv2.dilate(obj, kernel) & zone
    return obj


def _start_sector(distances: np.ndarray, tolerance: float = 0.08) -> int:
    """The sector to start from: the largest distance. Symmetric shapes have several (nearly) equal
    largest distances, e.g. the 4 corners of a rectangle; among those within ``tolerance``
    (relative) of the maximum, take the one whose clockwise successors are largest (weights
    1/2, 1/4, ...), so mirror-image corners are told apart the same way in every frame."""
    candidates = np.flatnonzero(distances >= distances.max() * (1.0 - tolerance))
    if candidates.size == 1:
        return int(candidates[0])
    weights = 0.5 ** np.arange(1, SECTORS)
    ahead = [float(weights @ np.roll(distances, -c)[1:]) for c in candidates]
    return int(candidates[int(np.argmax(ahead))])


def _salient_distances(
    contour: np.ndarray, cx: float, cy: float, area: float
) -> tuple[np.ndarray, np.ndarray]:
    """Step 6: the largest distance per 22.5-degree sector, largest first, clockwise."""
    pts = contour.reshape(-1, 2).astype(np.float64)
    dx, dy = pts[:, 0] - cx, pts[:, 1] - cy
    dist = np.hypot(dx, dy)
    # atan2 with y pointing down grows clockwise on screen.
    sector = (np.floor((np.arctan2(dy, dx) % (2 * np.pi)) / (2 * np.pi / SECTORS)).astype(int)) % SECTORS
    best = np.full(SECTORS, -1.0)
    idx = np.full(SECTORS, -1)
    order = np.lexsort((dist, sector))  # per sector, the last index holds the largest distance
    last = np.r_[sector[order][1:] != sector[order][:-1], True]
    best[sector[order][last]] = dist[order][last]
    idx[sector[order][last]] = order[last]
    points = np.where(idx[:, None] >= 0, pts[np.maximum(idx, 0)], [cx, cy])
    # Squash d / sqrt(A) (about 0.56 for a disc, > 1 for long shapes) into [0, 1).
    distances = 1.0 - np.exp(-np.maximum(best, 0.0) / np.sqrt(area))
    start = _start_sector(distances)
    return np.roll(distances, -start), np.roll(points, -start, axis=0)


def _refine_mask(frame: np.ndarray, small_mask: np.ndarray) -> np.ndarray:
    """Upsample the working-resolution mask to the frame; on the uncertain boundary band, give each
    pixel to the object or the background by which mean colour (from the frame) it is nearer."""
    height, width = frame.shape[:2]
    up = cv2.resize(small_mask.astype(np.float32), (width, height), interpolation=cv2.INTER_LINEAR)
    full = (up >= 0.5).astype(np.uint8)
    if small_mask.shape[1] == width:
        return full
    pad = 2 * round(width / small_mask.shape[1]) + 2
    x, y, bw, bh = cv2.boundingRect(full)
    x0, y0 = max(x - pad, 0), max(y - pad, 0)
    x1, y1 = min(x + bw + pad, width), min(y + bh + pad, height)
    roi_up = up[y0:y1, x0:x1]
    roi = frame[y0:y1, x0:x1].astype(np.float32)
    sure_obj = roi_up >= 0.99
    kernel = np.ones((3, 3), np.uint8)
    band = cv2.dilate(((roi_up > 0.01) & ~sure_obj).astype(np.uint8), kernel).astype(bool)
    ring = cv2.dilate((roi_up > 0.01).astype(np.uint8), kernel, iterations=pad // 2).astype(bool) & ~(
        roi_up > 0.01
    )
    if not sure_obj.any() or not ring.any():
        return full
    d_obj = np.linalg.norm(roi - roi[sure_obj].mean(axis=0), axis=2)
    d_bg = np.linalg.norm(roi - np.median(roi[ring], axis=0), axis=2)
    refined = np.where(band, d_obj < d_bg, roi_up >= 0.5)
    full[y0:y1, x0:x1] = refined.astype(np.uint8)
    return full


def _analyse(frame: np.ndarray, params: VisionParams, keep: bool = False) -> _Result:
    frame = _check_frame(frame)
    height, width = frame.shape[:2]
    work_w = min(params.work_width, width)
    work_h = max(MIN_SIDE // 2, round(height * work_w / width))
    small = cv2.resize(frame, (work_w, work_h), interpolation=cv2.INTER_AREA) if work_w != width else frame
    small_mask, info = _select_object(small, params, keep)
    result = _Result(
        np.zeros(FEATURES, np.float32),
        False,
        small_ms=info.get("ms"),
        small_sat=info.get("sat"),
        small_edges=info.get("edges"),
    )
    if small_mask is None:
        return result
    # Step 5: the mask at full resolution, then its largest external contour.
    full_mask = _refine_mask(frame, small_mask)
    contours, _ = cv2.findContours(full_mask, cv2.RETR_EXTERNAL, cv2.CHAIN_APPROX_NONE)
    if not contours:
        return result
    contour = max(contours, key=cv2.contourArea)
    m = cv2.moments(contour)
    if m["m00"] <= 1.0:
        return result
    area = m["m00"]
    cx, cy = m["m10"] / area, m["m01"] / area  # centre of mass
    distances, ray_points = _salient_distances(contour, cx, cy, area)
    filled = np.zeros((height, width), np.uint8)
    cv2.drawContours(filled, [contour], -1, 255, thickness=cv2.FILLED)
    rgb = np.array(cv2.mean(frame, mask=filled)[:3]) / 255.0  # step 7, mean R, G, B inside the contour
    if params.white_balance == "grey_world":
        rgb = rgb * info["gains"]
    features = np.concatenate([distances, np.clip(rgb, 0.0, 1.0), [cx / width, cy / height]])
    result.features = np.clip(features, 0.0, 1.0).astype(np.float32)
    result.found = True
    result.contour, result.centre, result.ray_points, result.mask = contour, (cx, cy), ray_points, filled
    return result


def extract_features(frame_rgb: np.ndarray, params: VisionParams | None = None) -> np.ndarray:
    """One RGB uint8 frame -> ``[21]`` float32: 16 distances, mean R, G, B, centroid x, y (all zeros if
    no object is found)."""
    return _analyse(frame_rgb, params or VisionParams()).features


def pipeline_steps(frame_rgb: np.ndarray, params: VisionParams | None = None) -> VisionSteps:
    """The same pipeline as :func:`extract_features`, keeping every intermediate image."""
    params = params or VisionParams()
    res = _analyse(frame_rgb, params, keep=True)
    frame = np.ascontiguousarray(frame_rgb)
    size = (frame.shape[1], frame.shape[0])

    def up(img: np.ndarray) -> np.ndarray:
        return cv2.resize(img, size, interpolation=cv2.INTER_NEAREST)

    contour_img = frame.copy()
    rays_img = frame.copy()
    thick = max(1, round(frame.shape[1] / 320))
    if res.found and res.contour is not None and res.centre is not None and res.ray_points is not None:
        cv2.drawContours(contour_img, [res.contour], -1, (0, 255, 0), thick)
        cv2.drawContours(rays_img, [res.contour], -1, (0, 255, 0), thick)
        centre = (round(res.centre[0]), round(res.centre[1]))
        for k, (x, y) in enumerate(res.ray_points):
            colour = (255, 0, 255) if k == 0 else (255, 255, 255)
            cv2.line(rays_img, centre, (round(x), round(y)), colour, thick, cv2.LINE_AA)
        cv2.circle(rays_img, centre, 2 * thick + 1, (255, 0, 0), cv2.FILLED)
    mask = res.mask if res.mask is not None else np.zeros(frame.shape[:2], np.uint8)
    return VisionSteps(
        original=frame.copy(),
        mean_shift=up(res.small_ms),
        saturation=up(res.small_sat),
        edges=up(res.small_edges),
        object_mask=mask,
        contour=contour_img,
        rays=rays_img,
        features=res.features,
        found=res.found,
    )


def encode_frames_found(
    frames: np.ndarray, workers: int = 2, params: VisionParams | None = None
) -> tuple[np.ndarray, np.ndarray]:
    """Encode a recording ``[T, H, W, 3]`` -> (``[T, 21]`` float32, ``[T]`` bool: object found).

    Frames without an object take the features of the nearest earlier frame with one (the nearest
    later one before the first detection); a recording without any object stays all zeros.
    ``workers`` threads share the frames (OpenCV releases the GIL)."""
    params = params or VisionParams()
    arr = frames if isinstance(frames, np.ndarray) else np.asarray(frames)
    if arr.ndim != 4 or arr.shape[-1] != 3:
        raise ValueError(f"frames must have shape T x H x W x 3 (RGB), got {arr.shape}")
    if arr.shape[0] == 0:
        raise ValueError("frames is empty (0 time steps)")
    _check_frame(arr[0])  # dtype and size, with a clear message, before starting workers

    def one(t: int) -> _Result:
        return _analyse(arr[t], params)

    if workers <= 1 or arr.shape[0] == 1:
        results = [one(t) for t in range(arr.shape[0])]
    else:
        with ThreadPoolExecutor(max_workers=workers) as pool:
            results = list(pool.map(one, range(arr.shape[0])))
    features = np.stack([r.features for r in results])
    found = np.array([r.found for r in results])
    if found.any() and not found.all():
        hits = np.flatnonzero(found)
        prev = np.searchsorted(hits, np.arange(len(found)), side="right") - 1
        source = hits[np.maximum(prev, 0)]  # nearest earlier detection, or the first one
        features = features[source]
        logger.debug("no object in %d of %d frames; filled from neighbours", (~found).sum(), len(found))
    return features, found


def encode_frames(frames: np.ndarray, workers: int = 2, params: VisionParams | None = None) -> np.ndarray:
    """Encode a recording ``[T, H, W, 3]`` RGB uint8 -> ``[T, 21]`` float32 (see module docstring)."""
    return encode_frames_found(frames, workers, params)[0]
