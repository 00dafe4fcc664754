"""The parameter vector's layout: the C core's constants, the slices and indices, split and
join."""
from __future__ import annotations

import re
from pathlib import Path

import numpy as np
import pytest

from harness.robot.layout import ParameterLayout, core_layout

HEADER = Path(__file__).resolve().parents[3] / "fmu" / "src" / "core" / "rigid_body.h"


def _header_constants() -> dict[str, int]:
    """The integer #defines and enumerators of rigid_body.h, by name."""
    text = HEADER.read_text()
    found = {name: int(value) for name, value in
             re.findall(r"#define\s+(RB_\w+)\s+(\d+)\s*$", text, flags=re.MULTILINE)}
    for body in re.findall(r"enum\s*\{([^}]*)\}", text):
        found.update({name: int(value) for name, value in re.findall(r"(RB_\w+)\s*=\s*(\d+)", body)})
    return found


def test_the_sizes_and_offsets_are_the_c_cores():
    c = _header_constants()
    layout = core_layout()
    assert (layout.link_size, layout.friction_size) == (c["RB_LINK_PARAMETERS"],
                                                        c["RB_JOINT_FRICTION"])
    assert (layout.mass, layout.viscous, layout.coulomb) == (c["RB_MASS"], c["RB_VISCOUS"],
                                                             c["RB_COULOMB"])
    assert layout.first_moment == c["RB_FIRST_MOMENT"]
    assert ParameterLayout(3).first_moment(2) == slice(20 + c["RB_FIRST_MOMENT"],
                                                       23 + c["RB_FIRST_MOMENT"])


def test_the_sizes_of_a_robot_with_joint_terms():
    layout = ParameterLayout(3, 2)
    assert (layout.link_size, layout.friction_size) == (10, 2)
    assert (layout.link_end, layout.standard_size, layout.size) == (30, 36, 42)
    assert ParameterLayout(3).size == 36


def test_the_slices_and_indices():
    layout = ParameterLayout(3, 2)
    index = np.arange(layout.size)
    assert index[layout.links].tolist() == list(range(30))
    assert index[layout.friction].tolist() == list(range(30, 36))
    assert index[layout.standard].tolist() == list(range(36))
    assert index[layout.extra].tolist() == list(range(36, 42))
    assert index[layout.link(1)].tolist() == list(range(10, 20))
    assert [layout.mass(i) for i in range(3)] == index[layout.masses].tolist() == [0, 10, 20]
    assert [layout.viscous(i) for i in range(3)] == index[layout.viscous_levels].tolist() \
        == [30, 32, 34]
    assert [layout.coulomb(i) for i in range(3)] == index[layout.coulomb_levels].tolist() \
        == layout.coulomb_indices.tolist() == [31, 33, 35]
    assert [layout.term(i, j) for i in range(3) for j in range(2)] == list(range(36, 42))
    assert layout.indices(layout.friction).tolist() == list(range(30, 36))


def test_the_pieces_tile_the_vector():
    """Every index is in exactly one link, one joint's friction or one joint's term."""
    layout = ParameterLayout(4, 3)
    owners = np.zeros(layout.size, int)
    for i in range(layout.joints):
        owners[layout.link(i)] += 1
        owners[[layout.viscous(i), layout.coulomb(i)]] += 1
        owners[[layout.term(i, j) for j in range(layout.terms_per_joint)]] += 1
    assert np.all(owners == 1)


def test_split_and_join_round_trip():
    layout = ParameterLayout(2, 3)
    pi = np.random.default_rng(1).normal(size=layout.size)
    links, friction, terms = layout.split(pi)
    assert links.shape == (2, 10) and friction.shape == (2, 2) and terms.shape == (2, 3)
    assert friction[1, 0] == pi[layout.viscous(1)] and friction[1, 1] == pi[layout.coulomb(1)]
    assert terms[1, 2] == pi[layout.term(1, 2)] and links[1, 0] == pi[layout.mass(1)]
    assert np.array_equal(layout.join(links, friction, terms), pi)
    bare = ParameterLayout(2)
    links, friction, terms = bare.split(pi[bare.standard])
    assert terms.shape == (2, 0)
    assert np.array_equal(bare.join(links, friction), pi[bare.standard])


def test_a_vector_of_another_length_is_refused():
    layout = ParameterLayout(2, 1)
    with pytest.raises(ValueError, match="the layout has 26"):
        layout.split(np.zeros(24))
    with pytest.raises(ValueError, match="the layout has 26"):
        layout.join(np.zeros((2, 10)), np.zeros((2, 2)))
