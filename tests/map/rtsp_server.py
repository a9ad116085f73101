"""A real RTSP server for the live-source tests: GStreamer's (Debian's ``gir1.2-gst-rtsp-server-1.0``,
installed by ``make test``) serving one Motion-JPEG AVI file at ``rtsp://127.0.0.1:PORT/NAME`` in real
time (RTP/JPEG, RFC 2435), as an IP camera does.

Run with the system Python, which has PyGObject (``python3-gi``), not the project's virtualenv::

    python3 rtsp_server.py PORT NAME FILE.avi      # PORT 0: any free port

It prints ``ready PORT`` once it listens, and serves until it is killed. ffmpeg makes the file from a
synthetic video: ``ffmpeg -i west.mp4 -c:v mjpeg -q:v 3 west.avi``.
"""

from __future__ import annotations

import sys


def main(argv: list[str]) -> int:
    import gi
    gi.require_version("Gst", "1.0")
    gi.require_version("GstRtspServer", "1.0")
    from gi.repository import GLib, Gst, GstRtspServer

    port, name, path = argv
    Gst.init(None)
    server = GstRtspServer.RTSPServer()
    server.set_address("127.0.0.1")
    server.set_service(port)
    factory = GstRtspServer.RTSPMediaFactory()
    # No decoding: the AVI's JPEG frames go into RTP packets as they are, at the file's frame rate.
    factory.set_launch(f'( filesrc location="{path}" ! avidemux ! rtpjpegpay name=pay0 pt=26 )')
    factory.set_shared(True)
    server.get_mount_points().add_factory(f"/{name}", factory)
    if server.attach(None) == 0:
        print(f"cannot listen on 127.0.0.1:{port}", file=sys.stderr)
        return 2
    print(f"ready {server.get_bound_port()}", flush=True)
    GLib.MainLoop().run()
    return 0


if __name__ == "__main__":
    sys.exit(main(sys.argv[1:]))
