"""What a preprocessing run did: the :class:`Summary` it returns (and the command line prints)."""

from __future__ import annotations

from dataclasses import dataclass, field

MB = 1e6


@dataclass
class Summary:
    """What a run did: clips ok / failed (this run and earlier ones it resumed), frames,
    bytes of BVH text read (what was read, not what files or archive members declare: a file
    read whole, a member's decompressed bytes; a clip refused or failing before its text was
    held counts 0), seconds in total and split into reading headers, kernels (reading
    and parsing the MOTION blocks, FK, features, contacts, model) and writing (headers and
    kernels summed over the threads or workers that ran them: they overlap)."""

    out: str
    clips_ok: int = 0
    clips_failed: int = 0
    clips_resumed: int = 0
    frames: int = 0
    bytes_read: int = 0
    seconds: float = 0.0
    headers_s: float = 0.0
    kernels_s: float = 0.0
    write_s: float = 0.0
    batches: int = 0
    finished: bool = False
    failures: list = field(default_factory=list)
    clips_mirrored: int = 0  # of clips_ok, the mirror images (--mirror)

    @property
    def mb_per_s(self) -> float:
        return self.bytes_read / MB / self.seconds if self.seconds > 0 else 0.0

    def lines(self) -> list[str]:
        state = "finished" if self.finished else "stopped early (rerun the same command to resume)"
        out = [
            f"{self.out}: {state}; {self.clips_ok} clips ok"
            + (f" ({self.clips_mirrored} of them mirror images)" if self.clips_mirrored else "")
            + f", {self.clips_failed} failed"
            + (f" ({self.clips_resumed} done by an earlier run)" if self.clips_resumed else ""),
            f"  {self.frames:,} frames, {self.bytes_read / MB:.1f} MB of BVH read this run in {self.seconds:.2f} s "
            f"({self.mb_per_s:.0f} MB/s)",
            f"  time: headers {self.headers_s:.2f} s, kernels (MOTION blocks, FK, features, contacts, model) "
            f"{self.kernels_s:.2f} s, writing {self.write_s:.2f} s (headers and kernels run in two threads or on a "
            "cluster's workers, overlapping the writing)",
        ]
        for failure in self.failures[:10]:
            out.append(f"  failed: {failure['error']}")
        if len(self.failures) > 10:
            out.append(f"  ... and {len(self.failures) - 10} more failures (see manifest.json)")
        return out


__all__ = ["MB", "Summary"]
