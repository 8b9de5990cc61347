# SPDX-License-Identifier: MIT
"""The step's line-search policy lives in one function (vpcontact.solver.line_search): the law
chooses, the contact parts' needs come on top, and ``cp`` wins where parts disagree."""

from __future__ import annotations

from types import SimpleNamespace

import pytest

from vpcontact.solver.line_search import line_search_for


def _law(linear_in_strain: bool, constant_tangent: bool):
    return SimpleNamespace(linear_in_strain=linear_in_strain, constant_tangent=constant_tangent)


class _Part:
    def __init__(self, wants: dict):
        self.wants, self.asked = wants, []

    def snes_defaults(self, linear_law: bool) -> dict:
        self.asked.append(linear_law)
        return dict(self.wants)


@pytest.mark.parametrize("linear, constant, expected", [
    (False, False, {"snes_linesearch_type": "l2"}),  # viscoplastic
    (True, False, {"snes_linesearch_type": "bt"}),  # the linearized scheme
    (True, True, {}),  # a linear law with a constant tangent: PETSc's full steps
])
def test_the_law_chooses_without_contact(linear, constant, expected):
    assert line_search_for(_law(linear, constant), []) == expected


def test_the_parts_needs_come_on_top_in_order_and_cp_wins_a_disagreement():
    rigid = _Part({"snes_type": "vinewtonrsls", "snes_linesearch_type": "cp",
                   "vpcontact_rescue_linesearch": "l2"})
    compliant = _Part({"snes_linesearch_type": "l2"})
    defaults = line_search_for(_law(False, False), [rigid, compliant])
    assert defaults == {"snes_type": "vinewtonrsls", "snes_linesearch_type": "cp",
                        "vpcontact_rescue_linesearch": "l2"}
    assert rigid.asked == compliant.asked == [False]
    # without cp the last part's wish stands over the law's
    assert line_search_for(_law(True, False), [_Part({"snes_linesearch_type": "l2"})]) == {
        "snes_linesearch_type": "l2"}
    assert line_search_for(_law(True, True), [_Part({"snes_type": "vinewtonrsls"})]) == {
        "snes_type": "vinewtonrsls"}
