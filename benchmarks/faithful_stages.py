"""Where `faithful` loses its training scenes, stage by stage (issue 13: the paper's learning rule).

Two measurements on one fold of the paper's 50:50 split (docs/experiments/faithful.md):

- `--auditory-only`: MTRNN_a alone on the fold's distinct training sentences, reproducing them
  closed-loop (eq. 5 with alpha = 0) every `--check-every` epochs: how many epochs the rule needs.
- otherwise: one `train(mode="faithful")` with the given overrides, then per stage: MTRNN_a
  alone from its learned c_a,0, the encoders' final LMS errors and code sizes, the assemblies'
  eq. (16) error against its minimum (`solve_assemblies` on the same codes), and train / test
  exact, F1 and edit distance with the trained assemblies and at that minimum.

    .venv/bin/python benchmarks/faithful_stages.py [--fold 0] [--seed 0]
        [--set training.epochs_somatosensory=4000 ...] [--auditory-only --epochs 5000 --check-every 250]

Prints one JSON object per line. One torch thread; a run with the Table 1 budgets and 5000
auditory epochs takes about 2.5 minutes on an idle core.
"""

from __future__ import annotations

import argparse
import json
import sys
import time
from pathlib import Path

import torch

sys.path.insert(0, str(Path(__file__).resolve().parents[1]))

from data.corpus import load_corpus  # noqa: E402
from model.config import MultiMTRNNConfig  # noqa: E402
from model.data import SequenceSet  # noqa: E402
from model.encoding.utterance import Lexicon, decode_text, text_to_phonemes  # noqa: E402
from model.experiments.evaluation import score, slot_vocabularies  # noqa: E402
from model.experiments.protocol import apply_overrides, run_seed  # noqa: E402
from model.experiments.splits import split_indices  # noqa: E402
from model.metrics import phoneme_f1, sentence_exact  # noqa: E402
from model.mtrnn import MTRNN  # noqa: E402
from model.training import train  # noqa: E402
from model.training.common import encode_utterances, make_batch  # noqa: E402
from model.training.faithful import assemblies_loss, distinct_rows, solve_assemblies, train_auditory  # noqa: E402
from server.commands.evaluate import parse_overrides  # noqa: E402

SCORES = ("sentence_exact", "f1", "edit_distance", "slot_action", "slot_colour", "slot_object")


def _said(activity: torch.Tensor, sentences: list[str], lexicon: Lexicon) -> dict[str, float]:
    """Closed-loop activity [B, T, |B|] against the sentences: exact and mean phoneme F1."""
    exact, f1 = 0, 0.0
    for a, sentence in zip(activity.numpy(), sentences, strict=True):
        phonemes, _, text = decode_text(a, lexicon)
        exact += sentence_exact(text, sentence)
        f1 += phoneme_f1(phonemes, text_to_phonemes(sentence))[2]
    return {"exact": round(exact / len(sentences), 3), "f1": round(f1 / len(sentences), 3)}


def auditory_budget(
    train_set: SequenceSet, config: MultiMTRNNConfig, epochs: int, every: int, seed: int
) -> None:
    """MTRNN_a alone on the distinct sentences, learning by `model.training.faithful.train_auditory`
    (its progress calls are where it is checked)."""
    sentences, _ = distinct_rows(train_set.utterances)
    lexicon = Lexicon.from_sentences(sentences)
    targets = encode_utterances(sentences, config.generation_steps)[0]
    net = MTRNN(config.auditory, torch.Generator().manual_seed(seed))
    started = time.perf_counter()

    def check(stage: str, epoch: int, total: int, loss: float, c0: torch.Tensor | None = None) -> None:
        if epoch % every == 0 and c0 is not None:
            with torch.no_grad():
                said = _said(net.generate(c0, targets.shape[1]), sentences, lexicon)
            line = {
                "epoch": epoch,
                "kld": round(loss, 3),
                **said,
                "seconds": round(time.perf_counter() - started),
            }
            print(json.dumps(line), flush=True)

    train_auditory(net, targets, config.training, torch.Generator().manual_seed(seed + 1), check, epochs)


def stages(
    train_set: SequenceSet, test_set: SequenceSet, config: MultiMTRNNConfig, seed: int, vocabularies
) -> dict:
    """One faithful training, then each stage's share of what is lost (module docstring)."""
    started = time.perf_counter()
    trained = train(train_set, mode="faithful", config=config, seed=seed)
    model, lexicon = trained.model, trained.lexicon
    last = {h["stage"]: round(h["loss"], 4) for h in trained.history}

    def scores(data: SequenceSet) -> dict:
        m = score(model, data, lexicon, vocabularies)
        return {k: round(m[k], 3) for k in SCORES}

    out = {"seconds": round(time.perf_counter() - started), "last_loss": last}
    out["train"], out["test"] = scores(train_set), scores(test_set)
    c_a0 = torch.as_tensor(trained.csc["auditory_c0"])
    with torch.no_grad():
        out["auditory_alone"] = _said(model.generate(c_a0), train_set.utterances, lexicon)
        b = make_batch(train_set, model.config)
        c_s, c_v = model.abstract(b.proprioception, b.vision, b.proprioception_lengths, b.vision_lengths)
        out["assemblies_error"] = round(assemblies_loss(model.assemblies, c_s, c_v, c_a0).item(), 4)
    out["code_abs"] = [round(c_s.abs().mean().item(), 3), round(c_v.abs().mean().item(), 3)]
    out["assemblies_minimum"] = round(solve_assemblies(model.assemblies, c_s, c_v, c_a0), 4)
    out["train_at_minimum"], out["test_at_minimum"] = scores(train_set), scores(test_set)
    return out


def main(argv: list[str] | None = None) -> None:
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("--fold", type=int, default=0)
    parser.add_argument(
        "--seed", type=int, default=None, help="default: the protocol's seed of (fold, init 0)"
    )
    parser.add_argument("--set", action="append", default=[], metavar="KEY=VALUE", help="config override")
    parser.add_argument("--auditory-only", action="store_true")
    parser.add_argument("--epochs", type=int, default=5000, help="--auditory-only: epochs")
    parser.add_argument("--check-every", type=int, default=250, help="--auditory-only: epochs between checks")
    args = parser.parse_args(argv)
    torch.set_num_threads(1)
    overrides = parse_overrides(args.set)
    config = MultiMTRNNConfig.from_dict(apply_overrides(MultiMTRNNConfig().to_dict(), overrides))
    data = load_corpus().training_data()
    train_idx, test_idx = split_indices(data.ids, data.utterances, args.fold)
    train_set, test_set = data.subset(train_idx), data.subset(test_idx)
    seed = run_seed(0, args.fold, 0) if args.seed is None else args.seed
    if config.training.optimiser is None:  # faithful's own rule
        config.training.optimiser = "paper"
    if args.auditory_only:
        auditory_budget(train_set, config, args.epochs, args.check_every, seed)
        return
    result = stages(train_set, test_set, config, seed, slot_vocabularies(data.utterances))
    print(json.dumps({"fold": args.fold, "seed": seed, "overrides": overrides, **result}), flush=True)


if __name__ == "__main__":
    main()
