"""The constraint graph a figure draws (issue: a drawn path must be an order the
plan keeps, and every constraint a path): :func:`goal_order` against
networkx's transitive closure and reduction, over generated demonstrations."""

from __future__ import annotations

import string

import networkx as nx
from hypothesis import given, settings
from hypothesis import strategies as st

from demoplan.learning.constraints import goal_order, learn_constraints, visit_sequence

TABLE_III = ["ABCDEFG", "AEHIJFG", "ACBFEDG"]


@st.composite
def demonstrations(draw: st.DrawFn) -> list[str]:
    """2–4 demonstrations over up to 8 states, each a random order of a random
    subset (states missing from some demonstrations make the constraints
    intransitive), sometimes with a state visited twice."""
    states = string.ascii_uppercase[: draw(st.integers(2, 8))]
    sequences = []
    for _ in range(draw(st.integers(2, 4))):
        chosen = draw(
            st.lists(st.sampled_from(states), min_size=1, max_size=len(states), unique=True)
        )
        sequence = draw(st.permutations(chosen))
        if draw(st.booleans()) and len(sequence) > 2:
            sequence = [*sequence, sequence[0]]  # a repeated visit: X ... X#2
        sequences.append("".join(sequence))
    return sequences


@settings(max_examples=300, deadline=None)
@given(sequences=demonstrations())
def test_drawn_edges_are_constraints_whose_closure_is_the_goals_order(sequences: list[str]) -> None:
    constraints = learn_constraints(sequences).constraints
    for sequence in sequences:
        order = goal_order(sequence, constraints)
        labels = visit_sequence(sequence)
        among = {(x, y) for x, y in constraints if x in labels and y in labels}
        graph = nx.DiGraph(among)
        graph.add_nodes_from(labels)
        closure = set(nx.transitive_closure_dag(graph).edges)
        drawn = nx.DiGraph(order.drawn)
        drawn.add_nodes_from(labels)
        assert order.constraints == among
        assert order.drawn <= among  # every drawn edge is a constraint
        assert set(nx.transitive_closure_dag(drawn).edges) == closure  # every constraint a path
        assert order.drawn == set(nx.transitive_reduction(graph).edges)  # nothing drawn twice
        assert order.implied == closure - among
        same_states = all(set(q) == set(sequences[0]) for q in sequences)
        if same_states and all(len(set(q)) == len(q) for q in sequences):
            # Every demonstration visits the same states once: the constraints
            # are the intersection of total orders, and the drawing says
            # exactly them.
            assert closure == among and not order.implied


def test_table_iii_goal_2_says_its_paths_order_e_before_f() -> None:
    """Demonstration 2 (A-E-H-I-J-F-G) keeps E<J and J<F, so E before F — the
    order demonstration 3 reverses in a goal without J. The drawing says so
    rather than implying it silently; the other two goals imply nothing extra."""
    constraints = learn_constraints(TABLE_III).constraints
    assert len(constraints) == 32
    orders = [goal_order(sequence, constraints) for sequence in TABLE_III]
    assert [sorted(o.implied) for o in orders] == [[], [("E", "F")], []]
    assert ("E", "F") not in constraints and ("F", "E") not in constraints
