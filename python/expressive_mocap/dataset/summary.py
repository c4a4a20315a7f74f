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
    rates: dict = field(
        default_factory=dict
    )  # the stored clips' frame rates (snapped) -> clips, mirror images not counted
    skeleton: dict | None = None  # the dataset's (manifest record: names, parents)

    @property
    def other_skeletons(self) -> int:
        """The failed clips of another skeleton than the dataset's (their records name their own)."""
        return sum("skeleton" in failure for failure in self.failures)

    @property
    def most_failed(self) -> bool:
        """Whether more clips failed than were stored (mirror images not counted): the command
        line exits 1 then, though the dataset of the clips that worked is written."""
        return self.clips_failed > self.clips_ok - self.clips_mirrored

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
        if self.other_skeletons:
            skeleton = self.skeleton or {"names": []}
            names = skeleton["names"]
            ours = f"{len(names)} joints, root {names[0]!r}" if names else "the first readable clip's"
            out.append(
                f"  {self.other_skeletons} of {self.clips_ok - self.clips_mirrored + self.clips_failed} clips are "
                f"of other skeletons than the dataset's ({ours}: the one most clips share) and failed; one dataset "
                "holds one skeleton: --canonical (canonical=True) retargets every clip onto one body"
            )
        if len(self.rates) > 1:
            counts = ", ".join(f"{n} at {rate:g} fps" for rate, n in sorted(self.rates.items()))
            out.append(
                f"  clips at {len(self.rates)} frame rates ({counts}), each stored at its own (the manifest's "
                "fps is null, each clip's record has its own): --fps F resamples every clip to one"
            )
        for failure in self.failures[:10]:
            out.append(f"  failed: {failure['error']}")
        if len(self.failures) > 10:
            out.append(f"  ... and {len(self.failures) - 10} more failures (see manifest.json)")
        return out


__all__ = ["MB", "Summary"]
