"""The robot's camera view of the table, rendered per time step with OpenCV drawing.

No 3-D engine: a pinhole camera (the NAO's bottom head camera, `Appearance` moves and varies it)
projects the table plane (a warped texture), the object (a ray-cast sphere for the apple,
extruded outlines for banana, dice and phone, flat-shaded by a directional light, with a soft
shadow) and the arm (capsules and boxes at the forward-kinematics positions, with its shadow).
Then lighting gradient, vignetting, exposure, white balance, blur and sensor noise.

Everything random lives in `Appearance` (drawn from a seed): the corpus varies camera pose and
field of view, light, table (wood grain, plain, cloth; base colour never as saturated as an
object), object shade, shape proportions, noise and blur, so that a model trained on it does not
learn one renderer. The object is always clearly more saturated than table and arm (the vision
encoder selects it by saturation), but shading, highlights, shadows and the hand occlude it.

Frames are RGB uint8 [T, H, W, 3]; `render_frames` is deterministic for a given appearance.

The package: `camera` (Appearance, the pinhole camera, `project`, `head_angles`), `raster` (drawing
helpers, arm, shadows, table), `objects` (apple, banana, dice, phone), `render` (`render_frames`).
"""

from data.camera.camera import HEIGHT, TABLE_KINDS, WIDTH, Appearance, head_angles, project
from data.camera.render import render_frames

__all__ = ["HEIGHT", "TABLE_KINDS", "WIDTH", "Appearance", "head_angles", "project", "render_frames"]
