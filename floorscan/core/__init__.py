"""What several stages need (../shared/ARCHITECTURE.md): imports point down to here only.

Modules: :mod:`floorscan.core.greedy` (lazy greedy maximum coverage, used by the select
stage's coverage orderings and the score stage's oracle) and :mod:`floorscan.core.geometry`
(points along wall segments).
"""
