"""A small synthetic world for the lesson tests, benchmark and screenshots while the shipped corpus
and model are not there: all 64 scenes x 2 teachers with proprioception that depends on the action
(and a little on the object), vision features per colour and shape, simple rendered frames, and two
untrained MultiMTRNNs (Table 1 sizes) saved as checkpoints. `load_world(settings)` is the app's
`Corpus` over it (`server.app.create_app(settings, load_world)`): the rest of the app runs the same
code as on the real artefacts."""

from __future__ import annotations

from pathlib import Path
from types import SimpleNamespace

import cv2
import numpy as np

from data import nao
from data.scenario import ACTIONS, SHAPES, all_scenes, recording_id
from model import checkpoint
from model.encoding import proprioception
from model.encoding.utterance import Lexicon
from model.multimtrnn import MultiMTRNN
from server.services.corpus import Corpus
from server.settings import Settings

RGB = {"blue": (40, 88, 220), "green": (40, 170, 70), "red": (210, 40, 40), "yellow": (230, 184, 0)}
SHAPE_PROFILE = {"apple": 0.45, "banana": 0.75, "dice": 0.5, "phone": 0.62}
VARIANTS = (0, 1)
FRAMES = 24


def _entry(scene, variant: int) -> SimpleNamespace:  # noqa: ANN001 - a data.scenario.Scene
    rng = np.random.default_rng([scene.index, variant])
    steps = int(rng.integers(40, 56))
    t = np.linspace(0.0, 1.0, steps)[:, None]
    a = ACTIONS.index(scene.action)
    prop = 0.5 + 0.3 * np.sin(np.pi * (a + 1) * t + np.arange(5)[None, :] * (0.4 + 0.1 * a))
    prop += 0.01 * SHAPES.index(scene.shape) * t + rng.normal(0.0, 0.01, prop.shape)
    prop = np.clip(prop, 0.0, 1.0).astype(np.float32)
    base = SHAPE_PROFILE[scene.shape]
    frame = np.concatenate(
        [base + 0.1 * np.cos(np.arange(16) * base), np.asarray(RGB[scene.colour]) / 255.0, [0.5, 0.6]]
    )
    vis = (np.repeat(frame[None, :], steps, axis=0) + rng.normal(0.0, 0.01, (steps, 21))).astype(np.float32)
    return SimpleNamespace(
        id=recording_id(scene, variant),
        scene=scene,
        variant=variant,
        joints=proprioception.decode_joints(prop, nao.JOINT_LIMITS),
        proprioception=prop,
        vision=vis,
        utterance=scene.utterance,
        teacher={},
        appearance={},
        object_found=1.0,
    )


def render(scene, frames: int = FRAMES) -> np.ndarray:  # noqa: ANN001 - a data.scenario.Scene
    """Frames [T, 240, 320, 3]: the object on a grey table, moved by the action, an arm from the edge."""
    out = np.empty((frames, 240, 320, 3), np.uint8)
    direction = {"pull": (0, 1), "push": (0, -1), "show me": (0, 0), "slide": (-1, 0)}[scene.action]
    for k in range(frames):
        img = np.full((240, 320, 3), (188, 184, 176), np.uint8)
        s = k / max(frames - 1, 1)
        cx, cy = int(170 + 50 * direction[0] * s), int(130 + 40 * direction[1] * s)
        colour = RGB[scene.colour]
        if scene.shape == "apple":
            cv2.circle(img, (cx, cy), 26, colour, -1)
        elif scene.shape == "banana":
            cv2.ellipse(img, (cx, cy), (40, 24), 0, 200, 340, colour, 14)
        elif scene.shape == "dice":
            cv2.rectangle(img, (cx - 22, cy - 22), (cx + 22, cy + 22), colour, -1)
        else:
            cv2.rectangle(img, (cx - 16, cy - 32), (cx + 16, cy + 32), colour, -1)
        cv2.line(img, (319, 239), (cx + 30, cy + 20), (120, 120, 125), 16)
        out[k] = img
    return out


def build(root: Path) -> Settings:
    """Write two untrained models under root/models and return the app's settings for them."""
    corpus_entries = [_entry(s, v) for s in all_scenes() for v in VARIANTS]
    ids = [e.id for e in corpus_entries]
    # a scene-wise split: each object is trained with two actions and held out with the other two
    train = [
        e.id for e in corpus_entries if (SHAPES.index(e.scene.shape) + ACTIONS.index(e.scene.action)) % 2 == 0
    ]
    test = [i for i in ids if i not in set(train)]
    lexicon = list(Lexicon.from_sentences([s.utterance for s in all_scenes()]).words)
    for name, mode, seed in (("faithful", "faithful", 0), ("end-to-end", "end_to_end", 1)):
        model = MultiMTRNN(seed=seed)
        model.eval()
        checkpoint.save(
            model,
            root / "models" / name,
            {"mode": mode, "seed": seed, "lexicon": lexicon, "split": {"train": train, "test": test}},
        )
    return Settings(
        models_dir=root / "models",
        model="faithful",
        viser=False,
        run_dir=root / "runs",
        user_dir=root / "user",
    )


def load_world(settings: Settings) -> Corpus:
    """The synthetic corpus (64 scenes x 2 teachers), its frames rendered by `render`."""
    entries = [_entry(s, v) for s in all_scenes() for v in VARIANTS]
    scenes = {e.id: e.scene for e in entries}
    world = SimpleNamespace(entries=entries, seed=0, path=None)
    return Corpus(world, settings.frame_cache, render=lambda rid, seed: render(scenes[rid]))
