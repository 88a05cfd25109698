"""Baseline agents for AmigoBot-v0: the analytic inverse-solution policy and SB3 helpers."""
