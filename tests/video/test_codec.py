"""harness.video: the simulation-time SEI, the h264 encoder's stream shape and determinism,
the stills and the depth PNG, against FFmpeg's own parsers and decoders (through PyAV)."""

from __future__ import annotations

import hashlib

import av
import numpy as np
import pytest

from harness.video import (
    SIM_TIME_UUID,
    H264Decoder,
    H264Encoder,
    H264Settings,
    decode_depth_png,
    encode_depth_png,
    encode_jpeg,
    encode_png,
    insert_sim_time,
    psnr,
    read_sim_time,
)
from harness.video.codec import decode_rgb
from harness.video.errors import VideoError
from harness.video.sei import nal_units, sim_time_sei

W, H = 96, 64


def _frames(n: int) -> list[np.ndarray]:
    """A smooth picture with a square moving across it."""
    y, x = np.mgrid[0:H, 0:W]
    base = np.stack([x * 255 // W, y * 255 // H, (x + y) * 255 // (W + H)], -1)
    out = []
    for k in range(n):
        img = base.astype(np.uint8).copy()
        img[20:40, 3 * k % (W - 20):3 * k % (W - 20) + 20] = (220, 40, 30)
        out.append(img)
    return out


@pytest.mark.parametrize("t", [0, 1, 3, 256, 2**32 + 3, 123_456_789_012, 2**63 - 1])
def test_sim_time_sei_round_trips_with_emulation_prevention(t: int) -> None:
    nal = sim_time_sei(t, 3)
    body = nal[1:]
    # no start code can appear inside the NAL unit, whatever the numbers
    assert b"\x00\x00\x00" not in body and b"\x00\x00\x01" not in body
    assert b"\x00\x00\x02" not in body
    au = b"\x00\x00\x00\x01\x09\xf0" + b"\x00\x00\x01\x65\x88\x80\x40"
    out = insert_sim_time(au, t, 3)
    types = [out[h] & 0x1F for _, h, _ in nal_units(out)]
    assert types == [9, 6, 5]  # after the delimiter, before the slice
    sei = read_sim_time(out)
    assert sei is not None and (sei.time_ns, sei.index) == (t, 3)
    assert read_sim_time(au) is None


def test_ffmpeg_reads_the_sei_as_user_data_unregistered() -> None:
    enc = H264Encoder(W, H, 30, H264Settings())
    units = [u for k, img in enumerate(_frames(3)) for u in enc.encode(img, k * 1000)]
    cc = av.CodecContext.create("h264", "r")
    for k, unit in enumerate(units):
        (frame,) = cc.decode(av.Packet(unit.data))
        blobs = [bytes(sd) for sd in frame.side_data if "SEI_UNREGISTERED" in str(sd.type)]
        ours = [b for b in blobs if b[:16] == SIM_TIME_UUID]
        assert len(ours) == 1
        assert int.from_bytes(ours[0][16:24], "big") == k * 1000
        assert int.from_bytes(ours[0][24:28], "big") == k


def test_h264_stream_shape_keyframes_and_quality() -> None:
    frames = _frames(25)
    enc = H264Encoder(W, H, 30, H264Settings(keyframe_interval=8))
    dec = H264Decoder()
    keys = []
    for k, img in enumerate(frames):
        (unit,) = enc.encode(img, k * 33_333_333, keyframe=(k == 13))
        assert (unit.time_ns, unit.index) == (k * 33_333_333, k)
        types = {unit.data[h] & 0x1F for _, h, _ in nal_units(unit.data)}
        if unit.keyframe:
            keys.append(k)
            assert {5, 7, 8} <= types  # IDR with SPS and PPS
        else:
            assert 5 not in types
        (out,) = dec.decode(unit.data)
        assert psnr(out, img) >= 30.0
    assert keys == [0, 8, 13, 16, 24]  # the interval, plus the one asked for


def test_x264_bytes_are_the_same_on_every_run() -> None:
    def digest(settings: H264Settings) -> str:
        enc = H264Encoder(W, H, 30, settings)
        h = hashlib.sha256()
        for k, img in enumerate(_frames(20)):
            for unit in enc.encode(img, k):
                h.update(unit.data)
        return h.hexdigest()

    assert digest(H264Settings()) == digest(H264Settings())
    assert digest(H264Settings(threads=2)) == digest(H264Settings(threads=2))
    assert digest(H264Settings(crf=30)) != digest(H264Settings())


def test_odd_sizes_and_wrong_frames_are_refused() -> None:
    with pytest.raises(VideoError, match="even width and height, got 95x64"):
        H264Encoder(95, 64, 30, H264Settings())
    enc = H264Encoder(W, H, 30, H264Settings())
    with pytest.raises(VideoError, match=r"expected a 96x64 RGB frame, got shape \(64, 95, 3\)"):
        enc.encode(np.zeros((64, 95, 3), np.uint8), 0)


def test_nvenc_opens_only_where_a_gpu_has_it() -> None:
    """Without an NVIDIA GPU (or with one without an encoder engine, such as the H100) the
    encoder fails to open with FFmpeg's reason; where it opens, it makes a decodable stream."""
    enc = H264Encoder(256, 192, 30, H264Settings(encoder="nvenc"), "cameras[0]")
    img = np.zeros((192, 256, 3), np.uint8)
    try:
        units = enc.encode(img, 0)
    except VideoError as err:
        assert str(err).startswith("cameras[0]: cannot open the nvenc h264 encoder "
                                   "(h264_nvenc): ")
        return
    (out,) = H264Decoder().decode(units[0].data)
    assert out.shape == img.shape


def test_stills_and_depth_png() -> None:
    img = _frames(1)[0]
    jpeg = encode_jpeg(img, 2)
    assert jpeg[:2] == b"\xff\xd8" and b"Lavc" not in jpeg  # bitexact: no version string
    assert psnr(decode_rgb(jpeg, "mjpeg"), img) >= 30.0
    assert len(encode_jpeg(img, 20)) < len(jpeg)
    png = encode_png(img)
    assert np.array_equal(decode_rgb(png, "png"), img)
    assert encode_png(img) == png

    depth = np.full((H, W), 2.5, np.float32)
    depth[0, :] = np.inf          # no return
    depth[1, :] = np.nan
    depth[2, :] = 70.0            # beyond 65.535 m: no return in 16 bits
    depth[3, :] = 0.0004          # rounds to 0 mm: no return
    depth[4, :] = 1.23449         # 1234 mm
    depth[5, :] = 65.535
    back = decode_depth_png(encode_depth_png(depth))
    assert back.dtype == np.float32
    assert np.isinf(back[:4]).all()
    assert back[4, 0] == np.float32(1.234) and back[5, 0] == np.float32(65.535)
    assert (back[6:] == np.float32(2.5)).all()
