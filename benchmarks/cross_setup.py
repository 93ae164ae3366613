"""Leave-one-setup-out on the wide corpus (issue 12): does what a model learns carry over to setups
it never saw?

Each held-out region is a part of the wide corpus's setup space, read from the recordings' labels
(`data.variety.labels`): a table-height band, a family of start postures, an IK preference, slow or
fast teachers, one object-shape variant, a camera band. Per region:

- train: the recordings of the training scenes (`split_indices(ids, utterances, 0, "scenes")`, the
  paper's 50:50 split by scene) that lie outside the region;
- test: the recordings of the test scenes (combinations never seen) that lie inside it.

Columns, per region and their mean over regions:

- probe: a logistic regression on each recording resampled to 24 steps predicting the action
  (docs: /work/shared/research/cross-setup.md), from the joint angles and from the hand's path
  relative to its start (NAO forward kinematics); seconds per region;
- default: the shipped default model (`data/artefacts/models/default`, trained on the paper's
  corpus) describing the same test recordings: sentence exact, action, colour, object;
- end_to_end: `model.training.train(mode="end_to_end", seed 0)` on the region's training
  recordings, with `--recipe` (a JSON object of `EndToEndOptions` overrides) on the defaults; one
  torch thread per process, `--workers` processes. `--no-train` leaves it out.

    .venv/bin/python benchmarks/cross_setup.py [--regions table-low,elbow-high]
        [--recipe '{"input_noise": 0.05}'] [--out cross_setup.json] [--no-train] [--workers 2]
"""

from __future__ import annotations

import argparse
import json
import sys
import time
from collections.abc import Callable
from concurrent.futures import ProcessPoolExecutor
from multiprocessing import get_context
from pathlib import Path

import numpy as np
from sklearn.linear_model import LogisticRegression
from sklearn.pipeline import make_pipeline
from sklearn.preprocessing import StandardScaler

sys.path.insert(0, str(Path(__file__).resolve().parents[1]))

from data.corpus import WIDE_PATH, Corpus, load_corpus  # noqa: E402
from data.nao import forward_kinematics_batch  # noqa: E402
from model.data import SequenceSet  # noqa: E402
from model.experiments.splits import split_indices  # noqa: E402

DEFAULT_MODEL = Path(__file__).resolve().parents[1] / "data" / "artefacts" / "models" / "default"
RESAMPLED_STEPS = 24
METRICS = {
    "exact": "sentence_exact",
    "action": "slot_action",
    "colour": "slot_colour",
    "object": "slot_object",
}

Rule = Callable[[dict], bool]
REGIONS: dict[str, tuple[str, Rule]] = {
    "table-low": ("table top below -0.085 m (paper -0.07)", lambda t: t["table_z"] < -0.085),
    "table-high": ("table top above -0.045 m", lambda t: t["table_z"] > -0.045),
    "posture-low-front": ("start posture: hand low, in front", lambda t: t["posture_family"] == "low-front"),
    "elbow-high": ("IK preference: elbow yaw below -0.5 rad", lambda t: t["elbow"] == "high"),
    "slow-teachers": ("recordings of 6.5 s or longer", lambda t: t["duration_s"] >= 6.5),
    "fast-teachers": ("recordings of 3 s or shorter", lambda t: t["duration_s"] <= 3.0),
    "apple-no-stem": ("object form: apple without stem", lambda t: t["form"] == "apple-no-stem"),
    "camera-high": ("camera 4 cm or more above the NAO's", lambda t: t["camera_height"] >= 0.165),
}


# ------------------------------------------------------------------------------------------ splits


def region_split(corpus: Corpus, rule: Rule) -> tuple[list[int], list[int]]:
    """(train, test) indices: training scenes outside the region, test scenes inside it."""
    ids = corpus.ids
    train, test = split_indices(ids, [e.utterance for e in corpus.entries], 0, "scenes")
    inside = [bool(e.labels) and rule(e.labels) for e in corpus.entries]
    return [i for i in train if not inside[i]], [i for i in test if inside[i]]


# ------------------------------------------------------------------------------------------- probe


def _resample(sequence: np.ndarray, steps: int = RESAMPLED_STEPS) -> np.ndarray:
    src = np.linspace(0.0, 1.0, len(sequence))
    dst = np.linspace(0.0, 1.0, steps)
    return np.stack([np.interp(dst, src, sequence[:, j]) for j in range(sequence.shape[1])], axis=1)


def probe_features(corpus: Corpus) -> dict[str, np.ndarray]:
    """Per recording: joint angles, and the hand path relative to its start, resampled to 24 steps."""
    joints = [_resample(e.joints).ravel() for e in corpus.entries]
    hands = []
    for e in corpus.entries:
        hand = forward_kinematics_batch(e.joints)["hand"]
        hands.append(_resample(hand - hand[0]).ravel())
    return {"joints": np.array(joints), "hand path": np.array(hands)}


def probe(features: np.ndarray, actions: np.ndarray, train: list[int], test: list[int]) -> float:
    """Action accuracy of a logistic regression fit on `train`, tested on `test`."""
    model = make_pipeline(StandardScaler(), LogisticRegression(max_iter=2000, C=1.0))
    model.fit(features[train], actions[train])
    return float((model.predict(features[test]) == actions[test]).mean())


# ------------------------------------------------------------------------------------------ models


def _scores(metrics: dict) -> dict[str, float]:
    return {name: float(metrics[key]) for name, key in METRICS.items()}


def baseline(data: SequenceSet, vocabularies: tuple, model_dir: Path = DEFAULT_MODEL) -> dict[str, float]:
    """The shipped default model's scores on `data`."""
    import torch

    from model import checkpoint
    from model.encoding.utterance import Lexicon
    from model.experiments.evaluation import score

    torch.set_num_threads(1)
    model, meta = checkpoint.load(model_dir)
    return _scores(score(model, data, Lexicon(meta["lexicon"]), vocabularies))


def train_and_score(task: tuple[str, SequenceSet, SequenceSet, dict, tuple]) -> dict:
    """Train end_to_end (seed 0, one thread) on the region's training set, score its test set."""
    import torch

    from model.experiments.evaluation import score
    from model.experiments.protocol import default_config
    from model.training import train

    region, train_set, test_set, recipe, vocabularies = task
    torch.set_num_threads(1)
    config = default_config("end_to_end")
    config["options"] = {**config.get("options", {}), **recipe}
    config["training"]["threads"] = 1
    start = time.perf_counter()
    trained = train(train_set, mode="end_to_end", config=config, seed=0)
    scores = _scores(score(trained.model, test_set, trained.lexicon, vocabularies))
    return {"region": region, **scores, "seconds": time.perf_counter() - start}


# -------------------------------------------------------------------------------------------- main


def run(corpus: Corpus, regions: list[str], recipe: dict, train_models: bool, workers: int) -> dict:
    from model.experiments.evaluation import slot_vocabularies

    data = corpus.training_data()
    vocabularies = slot_vocabularies(data.utterances)
    actions = np.array([e.scene.action for e in corpus.entries])
    start = time.perf_counter()
    features = probe_features(corpus)
    rows: dict[str, dict] = {}
    tasks = []
    for name in regions:
        train, test = region_split(corpus, REGIONS[name][1])
        if not test or len(set(actions[train])) < 2:
            raise SystemExit(f"region {name}: {len(test)} test and {len(train)} training recordings; too few")
        t0 = time.perf_counter()
        row: dict = {"description": REGIONS[name][0], "train": len(train), "test": len(test)}
        row["probe"] = {k: probe(f, actions, train, test) for k, f in features.items()}
        row["probe_seconds"] = time.perf_counter() - t0
        row["default"] = baseline(data.subset(test), vocabularies)
        rows[name] = row
        tasks.append((name, data.subset(train), data.subset(test), recipe, vocabularies))
    if train_models:
        with ProcessPoolExecutor(workers, mp_context=get_context("spawn")) as pool:
            for result in pool.map(train_and_score, tasks):
                rows[result.pop("region")]["end_to_end"] = result
    return {
        "corpus": str(corpus.path),
        "variety": corpus.variety,
        "recipe": recipe,
        "regions": rows,
        "mean": _means(rows),
        "seconds": time.perf_counter() - start,
    }


def _means(rows: dict[str, dict]) -> dict:
    out: dict = {"probe": {}, "default": {}, "end_to_end": {}}
    for column in out:
        values = [r[column] for r in rows.values() if column in r]
        if values:
            keys = [k for k in values[0] if k != "seconds"]
            out[column] = {k: float(np.mean([v[k] for v in values])) for k in keys}
    return out


def markdown(result: dict) -> str:
    """The table: one row per region and the mean."""
    slots = "exact / action / colour / object"
    head = (
        f"| region | train | test | probe joints | probe hand path | default {slots} | end_to_end {slots} |"
    )
    head += "\n|---|---|---|---|---|---|---|"

    def cells(scores: dict | None) -> str:
        return " / ".join(f"{scores[k]:.2f}" for k in METRICS) if scores else "-"

    lines = [head]
    for name, r in result["regions"].items():
        probe_cells = f"{r['probe']['joints']:.2f} | {r['probe']['hand path']:.2f}"
        lines.append(
            f"| {name} | {r['train']} | {r['test']} | {probe_cells} | {cells(r['default'])} | "
            f"{cells(r.get('end_to_end'))} |"
        )
    m = result["mean"]
    probe_mean = f"{m['probe']['joints']:.2f} | {m['probe']['hand path']:.2f}"
    lines.append(
        f"| **mean** | | | {probe_mean} | {cells(m['default'])} | {cells(m['end_to_end'] or None)} |"
    )
    return "\n".join(lines)


def _recipe(text: str | None) -> dict:
    if not text:
        return {}
    path = Path(text)
    value = json.loads(path.read_text() if path.suffix == ".json" and path.is_file() else text)
    if not isinstance(value, dict):
        raise SystemExit(f"--recipe must be a JSON object of EndToEndOptions overrides, got {text!r}")
    from dataclasses import fields

    from model.training.end_to_end.options import EndToEndOptions

    unknown = sorted(set(value) - {f.name for f in fields(EndToEndOptions)})
    if unknown:
        raise SystemExit(f"--recipe: unknown EndToEndOptions field(s) {unknown}")
    return value


def main(argv: list[str] | None = None) -> int:
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("--corpus", type=Path, default=WIDE_PATH, help="a wide corpus (labels per recording)")
    parser.add_argument(
        "--regions", default=",".join(REGIONS), help=f"comma-separated, of {', '.join(REGIONS)}"
    )
    parser.add_argument(
        "--recipe", default=None, help="JSON object (or .json file) of EndToEndOptions overrides"
    )
    parser.add_argument("--out", type=Path, default=None, help="write the result as JSON here")
    parser.add_argument("--no-train", action="store_true", help="probe and shipped default only")
    parser.add_argument("--workers", type=int, default=2, help="training processes (one torch thread each)")
    args = parser.parse_args(argv)
    regions = [r.strip() for r in args.regions.split(",") if r.strip()]
    unknown = [r for r in regions if r not in REGIONS]
    if unknown or not regions:
        parser.error(f"unknown region(s) {unknown}; choose from {', '.join(REGIONS)}")
    corpus = load_corpus(args.corpus)
    if corpus.variety != "wide":
        parser.error(
            f"{args.corpus} is a {corpus.variety!r} corpus; regions need a wide one (labels per recording)"
        )
    result = run(corpus, regions, _recipe(args.recipe), not args.no_train, max(1, args.workers))
    print(markdown(result))
    print(f"\n{len(regions)} regions in {result['seconds']:.0f} s wall time")
    if args.out:
        args.out.write_text(json.dumps(result, indent=2, sort_keys=True))
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
