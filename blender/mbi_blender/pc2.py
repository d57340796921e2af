"""A PC2 point cache written frame by frame into a temporary file, renamed into place only when complete.

PC2: "POINTCACHE2\\0", int32 version 1, int32 points, float32 start frame, float32 sample rate
(frames per sample), int32 samples, then samples x points x 3 float32, little-endian. Streaming
keeps one frame in memory (mbi.write_point_cache takes every frame at once).
"""
import os
import struct

import numpy as np


class Writer:
    def __init__(self, path, points, samples, start_frame, sample_rate=1.0):
        self.path, self.points, self.samples = path, points, samples
        self.temporary = "%s.%d.partial" % (path, os.getpid())
        self.written = 0
        self.file = open(self.temporary, "wb")
        self.file.write(b"POINTCACHE2\0" + struct.pack("<iiffi", 1, points, start_frame, sample_rate, samples))

    def write(self, positions):
        positions = np.ascontiguousarray(positions, dtype="<f4")
        if positions.shape != (self.points, 3):
            raise ValueError("%s: a frame of %s positions, the cache has %d points"
                             % (self.path, positions.shape, self.points))
        self.file.write(positions.tobytes())
        self.written += 1

    def commit(self):
        """Renames the complete cache into place; refuses a cache with frames missing."""
        self.file.close()
        if self.written != self.samples:
            self.discard()
            raise ValueError("%s: %d of %d frames written" % (self.path, self.written, self.samples))
        os.replace(self.temporary, self.path)

    def discard(self):
        self.file.close()
        if os.path.exists(self.temporary):
            os.remove(self.temporary)
