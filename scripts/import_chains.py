"""Print the longest chain of intra-package imports of a package, with grimp.

Usage: ``python scripts/import_chains.py twin`` prints the chain as JSON (its length
in modules and the modules in order, importer first).
"""

from __future__ import annotations

import functools
import json
import sys

import grimp


def longest_chain(package: str) -> list[str]:
    """The longest import path between two modules of ``package`` (the graph is acyclic
    when the package's layers hold; a cycle is broken where it is first met)."""
    graph = grimp.build_graph(package)
    modules = sorted(graph.modules)

    @functools.cache
    def longest_from(module: str, visiting: frozenset = frozenset()) -> tuple[str, ...]:
        best: tuple[str, ...] = (module,)
        for imported in sorted(graph.find_modules_directly_imported_by(module)):
            if imported in visiting or imported == module:
                continue
            chain = (module, *longest_from(imported, visiting | {module}))
            if len(chain) > len(best):
                best = chain
        return best

    return list(max((longest_from(module) for module in modules), key=len))


if __name__ == "__main__":
    chain = longest_chain(sys.argv[1] if len(sys.argv) > 1 else "twin")
    print(json.dumps({"modules_in_chain": len(chain), "chain": chain}, indent=1))
