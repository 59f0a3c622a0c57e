"""Post-dominators of a netlist's gates with respect to the observed signals (weak fault model).

Gate d *post-dominates* gate g when g's output is not observed and every path from g's output to an
observed signal passes through d. Then for any set S of gates, "S and g faulty" consistent implies
"S and d faulty" consistent: with d faulty its output is free, so make g healthy and recompute the
gates between g and d; nothing observed changes. So each diagnosis found stands for all the sets made
by moving its members up their post-dominator chains, and those need no SAT check (``engine``).

Computed once per set of observed signals, in reverse topological order: a gate's immediate
post-dominator is the nearest common ancestor, in the tree built so far, of the gates reading it
(and of the sink when its own output is observed). Gates that reach no observed signal get none.
"""
from __future__ import annotations

from collections.abc import Collection, Mapping, Sequence

SINK = ""  # the virtual node after every observed signal


def reverse_topological(readers: Mapping[str, Sequence[str]]) -> list[str]:
    """Gates ordered so that every gate comes after all the gates reading its output."""
    order: list[str] = []
    done: set[str] = set()
    for root in readers:
        if root in done:
            continue
        stack = [(root, iter(readers.get(root, ())))]
        done.add(root)
        while stack:
            node, children = stack[-1]
            child = next(children, None)
            if child is None:
                stack.pop()
                order.append(node)
            elif child not in done:
                done.add(child)
                stack.append((child, iter(readers.get(child, ()))))
    return order


def post_dominator_chains(order: Sequence[str], readers: Mapping[str, Sequence[str]],
                          observed: Collection[str]) -> dict[str, tuple[str, ...]]:
    """For each gate reaching an observed signal: itself followed by its post-dominators, nearest first.

    ``order`` is ``reverse_topological(readers)``; ``observed`` the gates whose outputs are observed.
    """
    parent: dict[str, str] = {SINK: SINK}
    depth: dict[str, int] = {SINK: 0}
    for gate in order:
        succ = [r for r in readers.get(gate, ()) if r in parent]
        if gate in observed:
            succ.append(SINK)
        if not succ:
            continue  # reaches nothing observed: never part of a conflict
        a = succ[0]
        for b in succ[1:]:
            while a != b:
                if depth[a] >= depth[b]:
                    a = parent[a]
                else:
                    b = parent[b]
        parent[gate] = a
        depth[gate] = depth[a] + 1
    chains: dict[str, tuple[str, ...]] = {}
    for gate in order:  # readers first, so a gate's post-dominators have their chains already
        if gate in parent:
            up = parent[gate]
            chains[gate] = (gate,) if up == SINK else (gate, *chains[up])
    return chains
