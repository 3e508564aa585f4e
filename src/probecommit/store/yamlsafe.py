"""The bounded YAML loader: every YAML the package reads (configs, ``--set`` values, a run's
``config.yaml``) goes through :func:`load_yaml`.

YAML's aliases (``*a``) and merge keys (``<<: *a``) let a few hundred bytes stand for
billions of nodes, and deep nesting makes every recursive pass slow. So the work is bounded
before anything is constructed: the text is limited in size, composed into a node graph
(aliases stay shared there, so this is linear in the text), then the graph is walked *as
construction would expand it* (every alias and every merged mapping counted each time it is
used), and refused as soon as the expanded node count or the depth passes its budget. Only
then are Python objects built, with the safe constructor (no ``!!python`` tags) and
duplicate keys refused. Every refusal is one line naming the source.
"""

from __future__ import annotations

from typing import Any

import yaml

from probecommit.errors import UserError

#: Largest YAML text read (bytes): a config with 100,000 fixed truth rows fits.
MAX_YAML_BYTES = 8 << 20
#: Most nodes after alias and merge-key expansion.
MAX_YAML_NODES = 2_000_000
#: Deepest nesting of collections.
MAX_YAML_DEPTH = 64

_Composer = getattr(yaml, "CSafeLoader", yaml.SafeLoader)


class YamlError(UserError, ValueError):
    """YAML that is malformed or over the budget; the message names the source."""


class _UniqueKeyLoader(yaml.SafeLoader):
    """Safe constructor that refuses a key given twice (YAML would keep the last silently)."""


def _construct_mapping(loader: _UniqueKeyLoader, node: yaml.MappingNode, deep: bool = False) -> dict:
    loader.flatten_mapping(node)
    seen: dict[Any, Any] = {}
    for key_node, _ in node.value:
        key = loader.construct_object(key_node, deep=deep)
        try:
            duplicate = key in seen
        except TypeError:  # unhashable key: let the base constructor report it
            break
        if duplicate:
            raise yaml.constructor.ConstructorError(
                None, None, f"duplicate key {key!r} (first at line {seen[key].start_mark.line + 1})", key_node.start_mark)
        seen[key] = key_node
    return loader.construct_mapping(node, deep=deep)


_UniqueKeyLoader.add_constructor(yaml.resolver.BaseResolver.DEFAULT_MAPPING_TAG, _construct_mapping)


def _error_line(source: str, exc: yaml.YAMLError) -> str:
    mark = getattr(exc, "problem_mark", None) or getattr(exc, "context_mark", None)
    where = f" at line {mark.line + 1}, column {mark.column + 1}" if mark is not None else ""
    problem = getattr(exc, "problem", None) or getattr(exc, "context", None) or str(exc).splitlines()[0]
    return " ".join(f"{source}: not valid YAML{where}: {problem}".split())


def check_budget(node: yaml.Node, source: str, max_nodes: int = MAX_YAML_NODES, max_depth: int = MAX_YAML_DEPTH) -> int:
    """The node count of ``node`` as construction expands it (every alias and merged mapping counted
    each time it is used), or :class:`YamlError` over ``max_nodes`` or ``max_depth``.

    Sizes and depths are computed once per composed node and summed (a post-order walk of the
    graph), so the check costs the text's size, not the expansion's.
    """
    size: dict[int, int] = {}
    depth: dict[int, int] = {}
    visiting: set[int] = set()
    stack: list[tuple[yaml.Node, bool]] = [(node, False)]
    while stack:
        current, ready = stack.pop()
        key = id(current)
        if key in size:
            continue
        children = ([n for pair in current.value for n in pair] if isinstance(current, yaml.MappingNode) else
                    list(current.value) if isinstance(current, yaml.SequenceNode) else [])
        if not ready:
            if key in visiting:  # its own ancestor: an alias inside the node it names
                raise YamlError(f"{source}: a recursive YAML alias (a node that contains itself); refusing it")
            visiting.add(key)
            stack.append((current, True))
            stack.extend((child, False) for child in children if id(child) not in size)
            continue
        visiting.discard(key)
        size[key] = 1 + sum(size.get(id(child), 0) for child in children)
        depth[key] = 1 + max((depth.get(id(child), 0) for child in children), default=0)
        if size[key] > max_nodes:
            raise YamlError(f"{source}: the YAML expands to more than {max_nodes:,} nodes (aliases and merge keys "
                            "counted each time they are used); refusing it")
        if depth[key] > max_depth:
            raise YamlError(f"{source}: the YAML nests deeper than {max_depth} levels; refusing it")
    return size[id(node)]


def load_yaml(text: str | bytes, source: str = "YAML") -> Any:
    """Parse ``text`` (one document) under the size, node and depth budgets, safely.

    Raises:
        YamlError: one line naming ``source``: too large, not YAML (with line and column),
            over the node or depth budget, an unsafe or unknown tag, or a duplicate key.
    """
    if isinstance(text, bytes):
        try:
            text = text.decode("utf-8")
        except UnicodeDecodeError as exc:
            raise YamlError(f"{source}: not UTF-8 text (byte {exc.start})") from None
    if len(text) > MAX_YAML_BYTES:
        raise YamlError(f"{source}: {len(text):,} characters of YAML, more than the {MAX_YAML_BYTES:,} accepted")
    try:
        node = yaml.compose(text, Loader=_Composer)
        if node is None:
            return None
        check_budget(node, source)
        loader = _UniqueKeyLoader("")
        try:
            return loader.construct_document(node)
        finally:
            loader.dispose()
    except yaml.YAMLError as exc:
        raise YamlError(_error_line(source, exc)) from None
    except RecursionError:
        raise YamlError(f"{source}: the YAML nests too deeply to read; refusing it") from None
    except (ValueError, TypeError) as exc:  # e.g. an unhashable key
        if isinstance(exc, YamlError):
            raise
        raise YamlError(" ".join(f"{source}: not a usable YAML document: {exc}".split())) from None
