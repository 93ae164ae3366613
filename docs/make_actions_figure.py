"""Draw docs/actions.png: the learner's view of each action over time (like Fig. 5d of the paper).

    .venv/bin/python docs/make_actions_figure.py [--out docs/actions.png] [--seed 0]

One row per action, five frames spread over the recording, rendered by data/camera/ from a
motion of data/motion.py. Deterministic for a seed.
"""

from __future__ import annotations

import argparse
import logging
from pathlib import Path

import matplotlib

matplotlib.use("Agg")
import matplotlib.pyplot as plt  # noqa: E402
import numpy as np  # noqa: E402

from data.camera import Appearance, render_frames  # noqa: E402
from data.motion import Teacher, generate_motion  # noqa: E402
from data.scenario import Scene  # noqa: E402

SCENES = (
    Scene("pull", "blue", "banana"),
    Scene("push", "red", "apple"),
    Scene("show me", "yellow", "phone"),
    Scene("slide", "green", "dice"),
)
FRAMES_PER_ROW = 5


def draw(out: Path, seed: int) -> Path:
    fig, axes = plt.subplots(len(SCENES), FRAMES_PER_ROW, figsize=(2.3 * FRAMES_PER_ROW, 1.95 * len(SCENES)))
    for row, scene in enumerate(SCENES):
        rng = np.random.default_rng([seed, scene.index])
        teacher = Teacher.sample(rng)
        motion = generate_motion(scene, teacher, rng)
        frames = render_frames(scene, motion, Appearance.sample(rng))
        steps = np.linspace(0, len(frames) - 1, FRAMES_PER_ROW).round().astype(int)
        for col, step in enumerate(steps):
            ax = axes[row, col]
            ax.imshow(frames[step])
            ax.set_xticks([])
            ax.set_yticks([])
            ax.set_title(f"t = {step / motion.fps:.1f} s", fontsize=8)
            if col == 0:
                ax.set_ylabel(f'"{scene.utterance}"', fontsize=8)
    fig.suptitle("Simulated NAO camera view over time, one row per action (cf. Fig. 5d)", fontsize=10)
    fig.tight_layout()
    fig.savefig(out, dpi=110)
    plt.close(fig)
    logging.getLogger(__name__).info("wrote %s", out)
    return out


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--out", type=Path, default=Path(__file__).resolve().parent / "actions.png")
    parser.add_argument("--seed", type=int, default=0)
    args = parser.parse_args()
    logging.basicConfig(level=logging.INFO)
    draw(args.out, args.seed)


if __name__ == "__main__":
    main()
