"""Simulation time inside an h264 stream: SEI "user data unregistered" messages.

Every access unit srr encodes carries one SEI NAL unit (type 6) with one message of payload
type 5 (user data unregistered, H.264 section D.1.7), placed before the access unit's first
slice. Its payload is :data:`SIM_TIME_UUID` (16 bytes) followed by 12 bytes, big-endian:

    uint64  simulation time of the frame, nanoseconds (the /clock value of its tick)
    uint32  frame index in the stream, from 0 (a gap means a frame was lost on the way)

Any h264 decoder skips SEI it does not know; FFmpeg hands it to applications as frame side
data (``AV_FRAME_DATA_SEI_UNREGISTERED``) and a consumer can equally read it from the
packets with :func:`read_sim_time`. The NAL unit is written with emulation prevention, so the
stream stays valid Annex B whatever the numbers are.
"""

from __future__ import annotations

import struct
import uuid
from collections.abc import Iterator
from dataclasses import dataclass

__all__ = [
    "SIM_TIME_UUID",
    "SimTime",
    "insert_sim_time",
    "nal_units",
    "read_sim_time",
    "sim_time_of_user_data",
    "sim_time_sei",
]

#: The UUID that marks srr's simulation-time SEI: uuid5(NAMESPACE_URL, "srr:sim_time_ns").
SIM_TIME_UUID = uuid.uuid5(uuid.NAMESPACE_URL, "srr:sim_time_ns").bytes
_PAYLOAD = struct.Struct(">QI")
_SEI_NAL = 6
_USER_DATA_UNREGISTERED = 5


@dataclass(frozen=True)
class SimTime:
    """What one frame's SEI says: its simulation time (ns) and its index in the stream."""

    time_ns: int
    index: int


def _escape(rbsp: bytes) -> bytes:
    """Emulation prevention: a 0x03 after every two zero bytes followed by a byte <= 3."""
    out = bytearray()
    zeros = 0
    for b in rbsp:
        if zeros >= 2 and b <= 3:
            out.append(3)
            zeros = 0
        out.append(b)
        zeros = zeros + 1 if b == 0 else 0
    return bytes(out)


def _unescape(ebsp: bytes) -> bytes:
    out = bytearray()
    zeros = 0
    for b in ebsp:
        if zeros >= 2 and b == 3:
            zeros = 0
            continue
        out.append(b)
        zeros = zeros + 1 if b == 0 else 0
    return bytes(out)


def _ff_coded(n: int) -> bytes:
    return b"\xff" * (n // 255) + bytes([n % 255])


def sim_time_sei(time_ns: int, index: int) -> bytes:
    """The SEI NAL unit (without start code) carrying ``time_ns`` and ``index``."""
    payload = SIM_TIME_UUID + _PAYLOAD.pack(int(time_ns), int(index) & 0xFFFFFFFF)
    rbsp = (_ff_coded(_USER_DATA_UNREGISTERED) + _ff_coded(len(payload)) + payload
            + b"\x80")  # rbsp_trailing_bits
    return bytes([_SEI_NAL]) + _escape(rbsp)


def nal_units(annexb: bytes) -> Iterator[tuple[int, int, int]]:
    """``(start of start code, start of NAL header, end)`` of each NAL unit of an Annex B
    byte stream (3- or 4-byte start codes)."""
    n = len(annexb)
    starts: list[tuple[int, int]] = []
    i = annexb.find(b"\x00\x00\x01")
    while i >= 0:
        code = i - 1 if i > 0 and annexb[i - 1] == 0 else i
        starts.append((code, i + 3))
        i = annexb.find(b"\x00\x00\x01", i + 3)
    for k, (code, head) in enumerate(starts):
        end = starts[k + 1][0] if k + 1 < len(starts) else n
        # trailing zero bytes belong to the next start code (or are padding)
        while end > head and annexb[end - 1] == 0 and k + 1 < len(starts):
            end -= 1
        yield code, head, end


def insert_sim_time(annexb: bytes, time_ns: int, index: int) -> bytes:
    """``annexb`` (one access unit) with the simulation-time SEI before its first slice."""
    sei = b"\x00\x00\x00\x01" + sim_time_sei(time_ns, index)
    for code, head, _end in nal_units(annexb):
        if 1 <= annexb[head] & 0x1F <= 5:  # the first VCL NAL unit (a slice)
            return annexb[:code] + sei + annexb[code:]
    return annexb + sei


def _ff_decoded(rbsp: bytes, i: int) -> tuple[int, int] | None:
    """What :func:`_ff_coded` wrote at ``i`` (an SEI payload type or size: a run of 0xFF
    bytes, 255 each, then the last byte) and the position after it; None when the buffer
    ends first."""
    value, n = 0, len(rbsp)
    while i < n and rbsp[i] == 0xFF:
        value += 255
        i += 1
    if i >= n:
        return None
    return value + rbsp[i], i + 1


def _sei_messages(rbsp: bytes) -> Iterator[tuple[int, bytes]]:
    i, n = 0, len(rbsp)
    while i < n and rbsp[i] != 0x80:
        ptype = _ff_decoded(rbsp, i)
        if ptype is None:
            return
        size = _ff_decoded(rbsp, ptype[1])
        if size is None:
            return
        i = size[1]
        yield ptype[0], rbsp[i:i + size[0]]
        i += size[0]


def sim_time_of_user_data(payload: bytes) -> SimTime | None:
    """The simulation time in one SEI user-data-unregistered payload (UUID + data), as
    decoders hand it over (FFmpeg: ``AV_FRAME_DATA_SEI_UNREGISTERED`` frame side data), or
    None when it is not srr's."""
    if len(payload) < 16 + _PAYLOAD.size or payload[:16] != SIM_TIME_UUID:
        return None
    t, idx = _PAYLOAD.unpack_from(payload, 16)
    return SimTime(t, idx)


def read_sim_time(annexb: bytes) -> SimTime | None:
    """The simulation time carried by an access unit (Annex B), or None when it has none."""
    for _code, head, end in nal_units(annexb):
        if annexb[head] & 0x1F != _SEI_NAL:
            continue
        for ptype, payload in _sei_messages(_unescape(annexb[head + 1:end])):
            found = sim_time_of_user_data(payload) if ptype == _USER_DATA_UNREGISTERED \
                else None
            if found is not None:
                return found
    return None
