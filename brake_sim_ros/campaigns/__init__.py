"""Campaigns: many runs from one file, varied along axes, split leak-free by unit.

:func:`load_campaign` reads a campaign file strictly; :meth:`Campaign.runs` resolves every
run (its scenario, seed, unit and split). ``brake-sim sweep`` runs them
(:mod:`brake_sim_ros.datasets.sweep`).
"""

from brake_sim_ros.campaigns.campaign import Campaign, CampaignError, RunSpec
from brake_sim_ros.campaigns.loader import builtin_campaigns, load_campaign, parse_campaign

__all__ = [
    "Campaign",
    "CampaignError",
    "RunSpec",
    "builtin_campaigns",
    "load_campaign",
    "parse_campaign",
]
