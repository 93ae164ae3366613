"""Epoch presets mean the same for every mode: they scale the epochs each mode actually reads."""

from __future__ import annotations

import pytest

from model.experiments.protocol import default_config
from server.jobs.presets import EPOCH_FIELDS, OPTION_DEFAULTS, PRESETS, scale_epochs


def _value(config: dict, dotted: str) -> int:
    *path, leaf = dotted.split(".")
    for part in path:
        config = config[part]
    return config[leaf]


def test_quick_scales_end_to_ends_own_epochs_not_only_training_epochs() -> None:
    quick = scale_epochs(default_config("end_to_end"), "end_to_end", PRESETS["quick"].scale)
    assert quick["options"]["auditory_epochs"] == 150  # of 1500
    assert quick["options"]["perception_epochs"] == 30  # of 300
    assert quick["options"]["auditory_check_every"] == 25  # of 250
    assert quick["options"]["joint_epochs"] == 0  # a stage left out stays out


@pytest.mark.parametrize("mode", sorted(EPOCH_FIELDS))
def test_every_epoch_field_of_every_mode_is_scaled(mode: str) -> None:
    full = scale_epochs(default_config(mode), mode, 1.0)
    quick = scale_epochs(default_config(mode), mode, 0.1)
    assert full == default_config(mode)  # the full preset is the mode's defaults, unchanged
    for dotted in EPOCH_FIELDS[mode]:
        leaf = dotted.rsplit(".", 1)[-1]
        before = OPTION_DEFAULTS[mode][leaf] if dotted.startswith("options.") else _value(full, dotted)
        assert _value(quick, dotted) == (0 if before == 0 else max(1, round(before * 0.1)))


def test_every_preset_has_a_measured_time_for_every_mode() -> None:
    for preset in PRESETS.values():
        assert set(preset.minutes) == set(EPOCH_FIELDS)
        assert all("about" in preset.label(mode) for mode in EPOCH_FIELDS)
    with pytest.raises(ValueError, match="> 0"):
        scale_epochs(default_config("peer"), "peer", 0)
