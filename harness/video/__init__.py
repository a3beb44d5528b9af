"""Camera video: h264, JPEG and PNG encoding (:mod:`~harness.video.codec`), simulation time
in the h264 stream (:mod:`~harness.video.sei`) and the RTSP servers
(:mod:`~harness.video.rtsp`, GStreamer's gst-rtsp-server). The bag path (compressed camera
topics) and the RTSP streams use the same encoders.

Names are imported from their submodules on first use (:mod:`harness._lazy`): reading the
simulation time of a stream loads no codec."""

from __future__ import annotations

from typing import TYPE_CHECKING

from harness._lazy import lazy_exports

if TYPE_CHECKING:
    from harness.video.codec import (
        DEPTH_PNG_FORMAT,
        ENCODERS,
        EncodedFrame,
        H264Decoder,
        H264Encoder,
        H264Settings,
        decode_depth_png,
        decode_rgb,
        encode_depth_png,
        encode_jpeg,
        encode_png,
        psnr,
    )
    from harness.video.sei import (
        SIM_TIME_UUID,
        SimTime,
        insert_sim_time,
        read_sim_time,
        sim_time_of_user_data,
    )

__all__ = [
    "DEPTH_PNG_FORMAT",
    "ENCODERS",
    "SIM_TIME_UUID",
    "EncodedFrame",
    "H264Decoder",
    "H264Encoder",
    "H264Settings",
    "SimTime",
    "decode_depth_png",
    "decode_rgb",
    "encode_depth_png",
    "encode_jpeg",
    "encode_png",
    "insert_sim_time",
    "psnr",
    "read_sim_time",
    "sim_time_of_user_data",
]

_WHERE = {
    "DEPTH_PNG_FORMAT": "codec",
    "ENCODERS": "codec",
    "EncodedFrame": "codec",
    "H264Decoder": "codec",
    "H264Encoder": "codec",
    "H264Settings": "codec",
    "decode_depth_png": "codec",
    "decode_rgb": "codec",
    "encode_depth_png": "codec",
    "encode_jpeg": "codec",
    "encode_png": "codec",
    "psnr": "codec",
    "SIM_TIME_UUID": "sei",
    "SimTime": "sei",
    "insert_sim_time": "sei",
    "read_sim_time": "sei",
    "sim_time_of_user_data": "sei",
}
__getattr__, __dir__ = lazy_exports(__name__, _WHERE, globals())
