"""Verification campaigns: many checks, sweeps over parameters, spread over Dask workers; a client of the
verification API (:mod:`genom2bip.verify`), never of the explorer's internals or of the command line.

``read_campaign`` reads a campaign file (genom2bip/campaign/spec.py), ``expand``
names its jobs (one per check, model, point of the sweep and target),
``run_job`` runs one where a worker runs it, and ``genom2bip campaign FILE``
(genom2bip/cli/campaign.py) runs them all on a cluster
(genom2bip/campaign/cluster.py), writing each record as it comes
(genom2bip/campaign/output.py).  The kinds of checks and of axes are
registries: genom2bip/campaign/kinds.py and genom2bip/campaign/axes.py.
"""
from __future__ import annotations

from genom2bip.campaign.jobs import Job, expand
from genom2bip.campaign.spec import Campaign, read_campaign
from genom2bip.campaign.worker import run_job

__all__ = ["Campaign", "Job", "expand", "read_campaign", "run_job"]
