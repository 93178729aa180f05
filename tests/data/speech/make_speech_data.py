"""Make the shipped test speech: English sentences spoken by espeak-ng, with their phone timing.

Run once (needs Debian's espeak-ng: ``apt-get install espeak-ng``); the test
run reads only the files this writes:

* ``<name>.wav`` / ``.flac``: the sentence with 0.3 s of silence before and
  after, in the format listed in ``SENTENCES`` (several rates, bit depths and
  channel counts, so the tests exercise resampling and mixing down);
* ``<name>.json``: the truth from espeak-ng's own phoneme events (the sample
  at which each phoneme starts, in IPA as espeak-ng names it) and word events.

    python tests/data/speech/make_speech_data.py

The sentences are Harvard sentences (IEEE 1969, public domain) and one made up;
the audio is espeak-ng's output, which its GPL does not cover.
"""

from __future__ import annotations

import ctypes
import json
from pathlib import Path

import numpy as np
import soundfile as sf
from scipy.signal import resample_poly

HERE = Path(__file__).parent
PAD = 0.3
# name, text (Harvard sentences, IEEE 1969), voice, words/min, output rate, subtype, channels, extension
SENTENCES = [
    ("birch", "The birch canoe slid on the smooth planks.", "en-us", 175, 22050, "PCM_16", 1, "wav"),
    ("glue", "Glue the sheet to the dark blue background.", "en-us", 160, 16000, "PCM_24", 2, "wav"),
    ("well", "It's easy to tell the depth of a well.", "en-us+m3", 150, 44100, "PCM_24", 1, "flac"),
    ("chicken", "These days a chicken leg is a rare dish.", "en-us+f2", 170, 16000, "PCM_16", 1, "wav"),
    # words in no dictionary: the aligner must pronounce them by rule
    ("blicket", "A glorp snarfed the blicket.", "en-us", 160, 16000, "PCM_16", 1, "wav"),
]


class _Id(ctypes.Union):
    _fields_ = [("number", ctypes.c_int), ("name", ctypes.c_char_p), ("string", ctypes.c_char * 8)]


class _Event(ctypes.Structure):
    _fields_ = [
        ("type", ctypes.c_int),
        ("unique_identifier", ctypes.c_uint),
        ("text_position", ctypes.c_int),
        ("length", ctypes.c_int),
        ("audio_position", ctypes.c_int),
        ("sample", ctypes.c_int),
        ("user_data", ctypes.c_void_p),
        ("id", _Id),
    ]


_CALLBACK = ctypes.CFUNCTYPE(ctypes.c_int, ctypes.POINTER(ctypes.c_short), ctypes.c_int, ctypes.POINTER(_Event))
_WORD, _PHONEME = 1, 7


def speak(text: str, voice: str, wpm: int):
    """(samples float64, rate, events) from libespeak-ng with phoneme events in IPA."""
    lib = ctypes.CDLL("libespeak-ng.so.1")
    samples, events = [], []

    def callback(wav, n, ev):
        if n > 0:
            samples.append(np.ctypeslib.as_array(wav, (n,)).astype(np.float64) / 32768.0)
        i = 0
        while ev[i].type != 0:
            e = ev[i]
            name = bytes(e.id.string).split(b"\0")[0].decode("utf-8") if e.type == _PHONEME else None
            events.append(
                {"type": e.type, "text_position": e.text_position, "length": e.length, "sample": e.sample, "name": name}
            )
            i += 1
        return 0

    cb = _CALLBACK(callback)
    rate = lib.espeak_Initialize(2, 0, None, 1 | 2)  # synchronous; phoneme events, IPA names
    lib.espeak_SetSynthCallback(cb)
    lib.espeak_SetVoiceByName(voice.encode())
    lib.espeak_SetParameter(1, wpm, 0)  # espeakRATE
    data = text.encode()
    lib.espeak_Synth(data, len(data) + 1, 0, 1, 0, 0, None, None)
    lib.espeak_Synchronize()
    return np.concatenate(samples), rate, events


def truth(text: str, events, rate: int) -> dict:
    """Phones and words with times (seconds, before padding) from espeak-ng's events."""
    phones, words = [], []
    marks = [e for e in events if e["type"] == _PHONEME]
    word_starts = {e["text_position"]: e for e in events if e["type"] == _WORD}
    for k, e in enumerate(marks[:-1]):
        if not e["name"]:
            continue  # a pause marker: the previous phone ends here
        end = marks[k + 1]["sample"]
        phones.append({"ipa": e["name"], "start": e["sample"] / rate, "end": end / rate, "word": e["text_position"]})
    # espeak-ng joins unstressed function words to their neighbour ("on the" is
    # one word event), so a truth "word" is the text from one word event to the next
    positions = sorted(word_starts)
    for k, pos in enumerate(positions):
        mine = [p for p in phones if p["word"] == pos]
        stop = positions[k + 1] - 1 if k + 1 < len(positions) else len(text)
        group = " ".join(w.strip(".,;:!?").lower() for w in text[pos - 1 : stop].split())
        words.append({"words": group, "start": mine[0]["start"], "end": mine[-1]["end"]})
    return {"phones": phones, "words": words}


def main():
    for name, text, voice, wpm, out_rate, subtype, channels, ext in SENTENCES:
        x, rate, events = speak(text, voice, wpm)
        t = truth(text, events, rate)
        x = np.concatenate([np.zeros(int(PAD * rate)), x, np.zeros(int(PAD * rate))])
        for item in t["phones"] + t["words"]:
            item["start"] = round(item["start"] + PAD, 5)
            item["end"] = round(item["end"] + PAD, 5)
        if out_rate != rate:
            x = resample_poly(x, out_rate, rate)
        x = 0.9 * x / np.abs(x).max()
        if channels == 2:  # a stereo file whose channels differ in level
            x = np.stack([x, 0.6 * x], axis=1)
        path = HERE / f"{name}.{ext}"
        sf.write(path, x, out_rate, subtype=subtype)
        meta = {
            "text": text,
            "audio": path.name,
            "voice": voice,
            "words_per_minute": wpm,
            "sample_rate": out_rate,
            "subtype": subtype,
            "channels": channels,
            "generator": "espeak-ng 1.51 (Debian) phoneme events, make_speech_data.py",
            **t,
        }
        (HERE / f"{name}.json").write_text(json.dumps(meta, indent=1, ensure_ascii=False) + "\n")
        print(name, path.stat().st_size, "bytes", len(t["phones"]), "phones")


if __name__ == "__main__":
    main()
