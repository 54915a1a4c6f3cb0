"""Exact tests of the recognition core, one file a stage."""
