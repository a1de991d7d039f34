"""A model of a campaign as plain, hashable, picklable parameters: what travels to a worker, which builds it there
with the verification API (and keeps it for the next job that names the same parameters)."""
from __future__ import annotations

from dataclasses import asdict, dataclass
from pathlib import Path
from typing import Any


#: The fields of the platform, the client and the response times: left out of a job's id when unset.
PLATFORM_FIELDS = ("platform", "client", "cores", "policy", "responses", "no_exceptions")


@dataclass(frozen=True)
class ModelParams:
    """The arguments of :func:`genom2bip.verify.build_model`, and of the variant of a sweep's point."""

    paths: tuple[str, ...]
    rules: str | None = None
    no_rules: bool = False
    defines: tuple[tuple[str, str], ...] = ()
    include_dirs: tuple[str, ...] = ()
    root: str | None = None
    # symbolic time (TimeSettings); None of them without ``timed``
    timed: bool = False
    tick_us: int | None = None
    default_wcet_us: int | None = None
    observers: str | None = None
    platform: str | None = None  # a platform file (genom2bip/platform.py); None: a core per task, or ``cores``
    client: str | None = None  # a mission file as the environment
    cores: int | None = None  # over the platform file's; without one, a platform of that many cores (EDF)
    policy: str | None = None  # over the platform file's
    responses: bool = False  # response-time observers (set by the response-times check)
    no_exceptions: bool = False  # codels end by their declared yields only
    # the variant (genom2bip.variants.Variant)
    wcet_scale: float = 1.0
    periods: tuple[tuple[str, int], ...] = ()

    def build(self):
        """The :class:`~genom2bip.verify.Model` of these parameters."""
        from genom2bip.variants import Variant
        from genom2bip.verify import TimeSettings, build_model

        time = (TimeSettings(tick_us=self.tick_us, default_wcet_us=self.default_wcet_us, observers=self.observers,
                             platform=self.platform, client=self.client, cores=self.cores, policy=self.policy,
                             responses=self.responses, exceptions=not self.no_exceptions)
                if self.timed else None)
        return build_model(list(self.paths), rules=self.rules, no_rules=self.no_rules, defines=dict(self.defines),
                           include_dirs=list(self.include_dirs), root=self.root, time=time,
                           variant=Variant(self.wcet_scale, self.periods))

    def identity(self, base: Path) -> dict[str, Any]:
        """The parameters with paths relative to ``base`` (the campaign file's directory): a job's id does not
        change when the project moves."""
        def rel(p: str | None) -> str | None:
            return None if p is None else _relative(p, base)

        data = asdict(self)
        data.update(paths=[rel(p) for p in self.paths], rules=rel(self.rules), observers=rel(self.observers),
                    platform=rel(self.platform), client=rel(self.client),
                    include_dirs=[rel(p) for p in self.include_dirs])
        for key in PLATFORM_FIELDS:  # unset, they leave the ids of campaigns written before they existed alone
            if data[key] in (None, False):
                del data[key]
        return data


def _relative(path: str, base: Path) -> str:
    import os

    return os.path.relpath(path, base)
