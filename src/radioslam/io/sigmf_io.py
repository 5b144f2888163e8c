"""SigMF recordings of waveform captures: one recording per pose.

Data: the 188 beam windows back to back, ``cf32_le``. Metadata:
  global       core fields, plus ``radioslam:`` sample rate, carrier, codebook bits,
               array size, hardware delay (the configured value, which the receiver
               must not use), pose index, window length and the full radio block;
  captures     one segment with ``core:frequency`` = carrier;
  annotations  one per beam window: ``radioslam:orientation``, ``beam_index``,
               ``beam_angle_rad``, ``ssb_index``, ``symbol_indices`` (PSS symbol then
               the R sensing symbols) and ``tx_bits`` (the transmitted payload, packed
               bits in base64), so the recording is self-contained for the receiver;
               with elevation beams also ``beam_elevation_rad`` and ``elevation_index``
               (absent: a flat scan, 0).
The data file is written first and the metadata last, each by write-then-rename:
a ``.sigmf-meta`` that exists describes a complete recording.
"""

from __future__ import annotations

import base64
from pathlib import Path

import numpy as np
import sigmf
from sigmf import SigMFFile
from sigmf.error import SigMFError as _SigMFLibraryError

from radioslam.capture import Capture, CaptureError, CaptureMode
from radioslam.config import RadioConfig
from radioslam.io.atomic import atomic_path
from radioslam.io.errors import SigMFError
from radioslam.io.json_io import read_json
from radioslam.io.sigmf_schema import check_meta

NS = "radioslam"
# the specification the library writes (sigmf < 1.2.1 has no __specification__: its version was the spec's)
SIGMF_SPECIFICATION = getattr(sigmf, "__specification__", sigmf.__version__)
EXTENSION = {"name": NS, "version": "1.0.0", "optional": False}
ANNOTATION_KEYS = ("orientation", "beam_index", "beam_angle_rad", "ssb_index", "symbol_indices", "tx_bits")
ELEVATION_KEYS = ("beam_elevation_rad", "elevation_index")  # optional: a flat scan's recording has none


def _pack_bits(bits: np.ndarray) -> str:
    return base64.b64encode(np.packbits(bits.astype(np.uint8)).tobytes()).decode("ascii")


def _unpack_bits(text: str, shape: tuple[int, ...]) -> np.ndarray:
    raw = np.frombuffer(base64.b64decode(text, validate=True), dtype=np.uint8)
    count = int(np.prod(shape))
    if len(raw) != -(-count // 8):  # unpackbits would pad a short payload with zeros
        raise ValueError(f"{len(raw)} bytes for {count} bits")
    return np.unpackbits(raw, count=count).reshape(shape)


def meta_path(base: str | Path) -> Path:
    return Path(str(base) + ".sigmf-meta")


def data_path(base: str | Path) -> Path:
    return Path(str(base) + ".sigmf-data")


def write_capture(capture: Capture, base: str | Path) -> Path:
    """Write ``base.sigmf-data`` and ``base.sigmf-meta``; returns the metadata path."""
    if capture.mode is not CaptureMode.WAVEFORM:
        raise SigMFError("only waveform-mode captures are IQ recordings", file=base, field="mode")
    radio, samples = capture.radio, np.ascontiguousarray(capture.samples, dtype="<c8")
    meta, data = meta_path(base), data_path(base)
    meta.unlink(missing_ok=True)
    with atomic_path(data) as tmp:
        samples.tofile(tmp)
    window = samples.shape[1]
    record = SigMFFile(data_file=str(data), global_info={
        "core:datatype": "cf32_le", "core:sample_rate": radio.sample_rate_hz,
        "core:version": SIGMF_SPECIFICATION, "core:num_channels": 1,
        "core:recorder": "radioslam simulator", "core:extensions": [EXTENSION],
        "core:description": f"pose {capture.pose_index}: {capture.n_beams} beam windows of {window} samples",
        f"{NS}:carrier_hz": radio.carrier_hz, f"{NS}:codebook_bits": radio.codebook_bits,
        f"{NS}:array_elements": radio.array_elements, f"{NS}:array_size": [radio.array_elements] * 2,
        f"{NS}:hardware_delay_s": radio.hardware_delay_s, f"{NS}:pose_index": capture.pose_index,
        f"{NS}:window_samples": window, f"{NS}:radio": radio.model_dump(mode="json"),
    })
    record.add_capture(0, metadata={"core:frequency": radio.carrier_hz})
    elevated = bool(np.any(capture.elevation_index != 0))
    for b in range(capture.n_beams):
        record.add_annotation(b * window, window, metadata={
            "core:label": f"o{capture.orientation[b]} i{capture.beam_index[b]:+d}",
            f"{NS}:orientation": int(capture.orientation[b]), f"{NS}:beam_index": int(capture.beam_index[b]),
            f"{NS}:beam_angle_rad": float(capture.beam_angle_rad[b]), f"{NS}:ssb_index": int(capture.ssb_index[b]),
            f"{NS}:symbol_indices": [int(s) for s in capture.symbol_indices[b]],
            f"{NS}:tx_bits": _pack_bits(capture.tx_bits[b]),
            **({f"{NS}:beam_elevation_rad": float(capture.beam_elevation_rad[b]),
                f"{NS}:elevation_index": int(capture.elevation_index[b])} if elevated else {}),
        })
    record.validate()
    with atomic_path(meta) as tmp, open(tmp, "w", encoding="utf-8") as handle:
        record.dump(handle, pretty=False)
    return meta


def _global(meta: dict, key: str, path: Path):
    try:
        return meta["global"][key]
    except KeyError:
        raise SigMFError("required field is missing", file=path, field=f"global.{key}") from None


def _radio_block(meta: dict, path: Path) -> dict:
    """The full ``radioslam:radio`` block, or for recordings made by other tools the
    individual global fields (carrier, codebook bits, array elements, optional
    hardware delay) on top of the defaults."""
    block = meta.get("global", {}).get(f"{NS}:radio")
    if block is not None:
        return block
    fields = {"carrier_hz": _global(meta, f"{NS}:carrier_hz", path),
              "codebook_bits": _global(meta, f"{NS}:codebook_bits", path),
              "array_elements": _global(meta, f"{NS}:array_elements", path)}
    if f"{NS}:hardware_delay_s" in meta["global"]:
        fields["hardware_delay_s"] = meta["global"][f"{NS}:hardware_delay_s"]
    return fields


def read_capture(base_or_meta: str | Path) -> Capture:
    """Read a recording written by :func:`write_capture` (or by hardware, in the same layout)."""
    text = str(base_or_meta)
    base = Path(text[: -len(".sigmf-meta")] if text.endswith(".sigmf-meta") else text)
    meta_file, data_file = meta_path(base), data_path(base)
    for f in (meta_file, data_file):
        if not f.exists():
            raise SigMFError("no such file", file=f, field="(file)")
    meta = read_json(meta_file, SigMFError)
    check_meta(meta, meta_file)
    try:
        radio = RadioConfig.model_validate(_radio_block(meta, meta_file))
    except ValueError as exc:
        raise SigMFError(f"invalid radio parameters: {exc.errors()[0]['msg']}", file=meta_file,
                         field=f"global.{NS}:radio") from None
    rate = _global(meta, "core:sample_rate", meta_file)
    if not isinstance(rate, (int, float)) or abs(rate - radio.sample_rate_hz) > 1e-6 * radio.sample_rate_hz:
        raise SigMFError(f"sample rate {rate} Hz does not match the radio's {radio.sample_rate_hz:.0f} Hz",
                         file=meta_file, field="global.core:sample_rate")
    if _global(meta, "core:datatype", meta_file) != "cf32_le":
        raise SigMFError("expected cf32_le samples", file=meta_file, field="global.core:datatype")
    window = int(_global(meta, f"{NS}:window_samples", meta_file))
    burst = (1 + radio.symbols_per_beam) * radio.fft_size  # the PSS symbol and R sensing symbols, without CPs
    if window < burst:
        raise SigMFError(f"a beam window of {window} samples cannot hold the burst of {1 + radio.symbols_per_beam} "
                         f"symbols of {radio.fft_size} samples", file=meta_file, field=f"global.{NS}:window_samples")
    expected = radio.beams_per_orientation * radio.orientations
    annotations = meta.get("annotations", [])
    if len(annotations) != expected:
        raise SigMFError(f"expected {expected} beam annotations, found {len(annotations)}",
                         file=meta_file, field="annotations")
    size = data_file.stat().st_size
    if size != expected * window * 8:
        raise SigMFError(f"truncated or oversized: {size // 8} samples, the annotations need "
                         f"{expected * window}", file=data_file, field="core:sample_count")
    try:
        record = SigMFFile(metadata=meta, data_file=str(data_file))  # verifies core:sha512
        samples = record.read_samples().reshape(expected, window)
    except (_SigMFLibraryError, ValueError, OSError, TypeError, KeyError, IndexError, AttributeError) as exc:
        # the library reading what the schema does not cover (captures, core fields) of the wrong type
        raise SigMFError(f"rejected by sigmf: {type(exc).__name__}: {exc}", file=meta_file,
                         field="(document)") from None
    fields = {k: [] for k in ANNOTATION_KEYS}
    r, width = radio.symbols_per_beam, 4 * radio.n_subcarriers
    for b, ann in enumerate(annotations):
        if ann.get("core:sample_start") != b * window or ann.get("core:sample_count") != window:
            raise SigMFError(f"beam window must start at {b * window} and span {window} samples",
                             file=meta_file, field=f"annotations[{b}].core:sample_start")
        for key in ANNOTATION_KEYS:
            if f"{NS}:{key}" not in ann:
                raise SigMFError("required field is missing", file=meta_file, field=f"annotations[{b}].{NS}:{key}")
        try:
            fields["tx_bits"].append(_unpack_bits(ann[f"{NS}:tx_bits"], (r, width)))
        except (ValueError, TypeError) as exc:
            raise SigMFError(f"not base64 of the packed payload bits ({exc})", file=meta_file,
                             field=f"annotations[{b}].{NS}:tx_bits") from None
        for key in ANNOTATION_KEYS[:-1]:
            fields[key].append(ann[f"{NS}:{key}"])
        for key in ELEVATION_KEYS:
            fields.setdefault(key, []).append(ann.get(f"{NS}:{key}", 0))
    try:
        pose_index = int(_global(meta, f"{NS}:pose_index", meta_file))
        return Capture(radio=radio, mode=CaptureMode.WAVEFORM, pose_index=pose_index,
                       orientation=np.array(fields["orientation"], dtype=np.int64),
                       beam_index=np.array(fields["beam_index"], dtype=np.int64),
                       beam_angle_rad=np.array(fields["beam_angle_rad"], dtype=np.float64),
                       ssb_index=np.array(fields["ssb_index"], dtype=np.int64),
                       symbol_indices=np.array(fields["symbol_indices"], dtype=np.int64),
                       tx_bits=np.stack(fields["tx_bits"]), samples=samples, source=str(data_file),
                       beam_elevation_rad=np.array(fields["beam_elevation_rad"], dtype=np.float64),
                       elevation_index=np.array(fields["elevation_index"], dtype=np.int64))
    except CaptureError:
        raise
    except (ValueError, TypeError) as exc:
        raise SigMFError(f"inconsistent annotations: {exc}", file=meta_file, field="annotations") from None
