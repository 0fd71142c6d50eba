"""A loopback MJPEG server for the camera tests: 127.0.0.1 only, bounded, in a daemon thread.

Serves ``multipart/x-mixed-replace`` JPEG frames (each different: the frame number is drawn in)
at ``fps``; after ``stall_after`` frames (or once ``stall`` is set) it stops sending but keeps the
connection open (a phone whose app froze), until the server shuts down or ``MAX_STALL_S`` passes.
``frames`` lists the JPEG bytes sent, in order, so a test can compare what the client received
byte for byte."""

from __future__ import annotations

import socketserver
import threading
import time

import cv2
import numpy as np

MAX_FRAMES = 2000
MAX_STALL_S = 10.0


def numbered_jpeg(k: int, size: tuple[int, int] = (320, 240)) -> bytes:
    img = np.full((size[1], size[0], 3), 40, np.uint8)
    cv2.circle(img, (size[0] // 2, size[1] // 2), 30 + k % 40, (0, 0, 255), 2)
    cv2.putText(img, str(k), (10, 30), cv2.FONT_HERSHEY_SIMPLEX, 1.0, (255, 255, 255), 2)
    return cv2.imencode(".jpg", img, [cv2.IMWRITE_JPEG_QUALITY, 80])[1].tobytes()


class LoopbackMjpeg:
    def __init__(self, fps: float = 30.0, stall_after: int | None = None, size: tuple[int, int] = (320, 240),
                 skip: frozenset[int] = frozenset()):
        self.fps, self.stall_after, self.size = fps, stall_after, size
        self.skip = skip  # frame numbers not sent: their time slot passes (a phone app's drop)
        self.frames: list[bytes] = []
        self.stop = threading.Event()
        self.stall = threading.Event()  # set: stop sending now (the connection stays open)
        owner = self

        class Handler(socketserver.StreamRequestHandler):
            def handle(self) -> None:
                self.rfile.readline()
                while self.rfile.readline() not in (b"\r\n", b"\n", b""):
                    pass
                self.wfile.write(b"HTTP/1.0 200 OK\r\nContent-Type: multipart/x-mixed-replace; "
                                 b"boundary=frame\r\n\r\n")
                for k in range(MAX_FRAMES):
                    if owner.stop.is_set():
                        return
                    if owner.stall.is_set() or (owner.stall_after is not None and k >= owner.stall_after):
                        owner.stop.wait(MAX_STALL_S)
                        return
                    jpeg = numbered_jpeg(k, owner.size)
                    if k in owner.skip:
                        time.sleep(1.0 / owner.fps)
                        continue
                    owner.frames.append(jpeg)
                    try:
                        self.wfile.write(b"--frame\r\nContent-Type: image/jpeg\r\nContent-Length: %d\r\n\r\n"
                                         % len(jpeg) + jpeg + b"\r\n")
                    except OSError:
                        return
                    time.sleep(1.0 / owner.fps)

        class Server(socketserver.ThreadingTCPServer):
            daemon_threads = True
            allow_reuse_address = True

        self.server = Server(("127.0.0.1", 0), Handler)
        self.url = f"http://127.0.0.1:{self.server.server_address[1]}/video"
        self.thread = threading.Thread(target=self.server.serve_forever, name="loopback-mjpeg", daemon=True)

    def __enter__(self) -> LoopbackMjpeg:
        self.thread.start()
        return self

    def __exit__(self, *exc: object) -> None:
        self.stop.set()
        self.server.shutdown()
        self.server.server_close()
