"""Solvers and steps: linear-solver choice, Newton, static, dynamic and multi-step runs."""
