"""Lesson 3, seeing: every stage of the vision pipeline (Fig. 7) on one frame, and the features."""

from __future__ import annotations

import base64
import io
import time

import cv2
import numpy as np
from PIL import Image

from model.encoding.vision import SECTORS, VISUAL_FEATURES, VisionParams, pipeline_steps
from server.lessons import rounded
from server.services.errors import Invalid, ServiceError, TooLarge

FEATURE_NAMES = [f"d{k + 1}" for k in range(SECTORS)] + ["R", "G", "B", "centroid x", "centroid y"]
MAX_IMAGE_WIDTH = 640  # uploads are scaled down to this width before the pipeline
MAX_IMAGE_SIDE = 4096  # pixels; checked from the header, before decoding


def _data_url(image: np.ndarray) -> str:
    """A stage image as a data URL: masks and edges (grey) as PNG, colour pictures as JPEG."""
    if image.ndim == 2:
        ok, buf = cv2.imencode(".png", image, [cv2.IMWRITE_PNG_COMPRESSION, 3])
        kind = "png"
    else:
        ok, buf = cv2.imencode(".jpg", cv2.cvtColor(image, cv2.COLOR_RGB2BGR), [cv2.IMWRITE_JPEG_QUALITY, 88])
        kind = "jpeg"
    if not ok:
        raise ServiceError("could not encode an image")
    return f"data:image/{kind};base64," + base64.b64encode(buf.tobytes()).decode("ascii")


def image_size(data: bytes) -> tuple[int, int]:
    """(width, height) from the picture's header alone (PIL's lazy open reads no pixel data)."""
    try:
        with Image.open(io.BytesIO(data)) as image:
            return image.size
    except Image.DecompressionBombError:
        raise TooLarge(
            f"the picture has more than {2 * Image.MAX_IMAGE_PIXELS / 1e6:.0f} million pixels; "
            f"at most {MAX_IMAGE_SIDE} pixels a side are accepted"
        ) from None
    except (OSError, ValueError, SyntaxError):
        raise Invalid("the upload is not an image that can be read (PNG, JPEG, BMP, ...)") from None


def decode_image(data: bytes) -> np.ndarray:
    """Uploaded bytes (PNG, JPEG, ...) -> RGB uint8, scaled down to at most MAX_IMAGE_WIDTH wide.

    The size is checked from the header before decoding (at most MAX_IMAGE_SIDE pixels a side),
    and the picture is decoded as stored (EXIF orientation ignored), so it has the header's size."""
    if not data:
        raise Invalid("the uploaded file is empty")
    width, height = image_size(data)
    if max(width, height) > MAX_IMAGE_SIDE:
        raise TooLarge(
            f"the picture is {width} x {height} pixels; at most {MAX_IMAGE_SIDE} pixels a side are accepted"
        )
    image = cv2.imdecode(np.frombuffer(data, np.uint8), cv2.IMREAD_COLOR | cv2.IMREAD_IGNORE_ORIENTATION)
    if image is None:
        raise Invalid("the upload is not an image OpenCV can read (PNG, JPEG, BMP, ...)")
    if image.shape[1] > MAX_IMAGE_WIDTH:
        h = round(image.shape[0] * MAX_IMAGE_WIDTH / image.shape[1])
        image = cv2.resize(image, (MAX_IMAGE_WIDTH, h), interpolation=cv2.INTER_AREA)
    return cv2.cvtColor(image, cv2.COLOR_BGR2RGB)


def seeing(frame: np.ndarray, colour_radius: int) -> dict:
    """Every stage of the vision pipeline on one RGB frame, and the 19 (+2) features."""
    if not 4 <= colour_radius <= 64:
        raise Invalid(f"colour_radius must be in 4..64, got {colour_radius}")
    started = time.perf_counter()
    try:
        steps = pipeline_steps(frame, VisionParams(colour_radius=colour_radius))
    except ValueError as err:
        raise Invalid(str(err)) from None
    ms = (time.perf_counter() - started) * 1e3
    stages = [
        ("original", "the camera frame", steps.original),
        ("mean_shift", "mean-shift segmentation", steps.mean_shift),
        ("saturation", "colour saturation (object candidates)", steps.saturation),
        ("edges", "Canny edges", steps.edges),
        ("object_mask", "the chosen object", steps.object_mask),
        ("contour", "its contour", steps.contour),
        ("rays", "centre of mass and 16 salient distances", steps.rays),
    ]
    return {
        "width": int(frame.shape[1]),
        "height": int(frame.shape[0]),
        "found": bool(steps.found),
        "pipeline_ms": round(ms, 1),
        "stages": [{"key": k, "title": t, "image": _data_url(img)} for k, t, img in stages],
        "features": rounded(steps.features, 4),
        "feature_names": FEATURE_NAMES[: len(steps.features)],
        "paper_features": VISUAL_FEATURES,
    }
