"""Reliability: every run ends (exits), long soaks."""
