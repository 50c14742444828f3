"""Saved detectors that are valid in shape but would crawl: a forest whose tree is a long
chain, or whose nodes have two parents, is refused in one line at load and at once; a tree
exactly as deep as fitting may make loads and predicts. Fitting never makes a deeper one.
Pure logic on detectors fitted on hand-made windows (``test_saved_file``'s).
"""

from __future__ import annotations

import base64
import json
import time
from pathlib import Path

import numpy as np
import pytest

from brake_sim_ros.detection import saved
from brake_sim_ros.detection.forest import LEAF, MAX_TREE_DEPTH, MAX_TREES, ForestArrays
from brake_sim_ros.detection.learned import LearnedClassifier
from tests.detection.test_saved_file import FITTED_ON, _windows


@pytest.fixture(scope="module")
def fitted() -> LearnedClassifier:
    d = LearnedClassifier()
    d.fit(_windows())
    return d


def _encoded(values: np.ndarray, dtype: str) -> dict:
    data = np.ascontiguousarray(values, dtype={"int64": "<i8", "float64": "<f8"}[dtype])
    return {"dtype": dtype, "shape": list(data.shape), "base64": base64.b64encode(data).decode()}


def _chain(depth: int, n_features: int, outputs: int) -> dict:
    """One tree: node 2j splits into the leaf 2j+1 and the node 2j+2, ``depth`` times."""
    n = 2 * depth + 1
    left = np.full(n, LEAF, dtype=np.int64)
    right = np.full(n, LEAF, dtype=np.int64)
    splits = np.arange(0, 2 * depth, 2)
    left[splits], right[splits] = splits + 1, splits + 2
    leaves = depth + 1
    return {
        "n_features": n_features,
        "node_counts": _encoded(np.array([n]), "int64"),
        "left": _encoded(left, "int64"),
        "right": _encoded(right, "int64"),
        "feature": _encoded(np.zeros(n, dtype=np.int64), "int64"),
        "threshold": _encoded(np.linspace(0.0, 1.0, n), "float64"),
        "leaf_values": _encoded(np.full((leaves, outputs), 1.0 / outputs), "float64"),
    }


def _document(fitted: LearnedClassifier, forest: dict) -> dict:
    doc = saved.document(fitted, fitted_on=FITTED_ON)
    doc["state"]["forest"] = forest
    return doc


def _write(tmp_path: Path, doc: dict) -> Path:
    path = tmp_path / "model.json"
    path.write_text(json.dumps(doc))
    return path


@pytest.mark.parametrize("depth", [MAX_TREE_DEPTH + 1, 10_000, 1_000_000])
def test_a_chain_deeper_than_fitting_makes_is_refused_at_once(fitted, tmp_path, depth):
    doc = saved.document(fitted, fitted_on=FITTED_ON)
    outputs = len(doc["state"]["classes"])
    doc["state"]["forest"] = _chain(depth, doc["state"]["forest"]["n_features"], outputs)
    path = _write(tmp_path, doc)
    start = time.perf_counter()
    with pytest.raises(saved.ModelFileError, match="deeper than") as info:
        saved.load(path, "learned")
    assert time.perf_counter() - start < 20.0  # the chain's depth is not walked node by node
    assert "\n" not in str(info.value)


def test_a_tree_as_deep_as_fitting_may_make_loads_and_predicts(fitted, tmp_path):
    doc = saved.document(fitted, fitted_on=FITTED_ON)
    outputs = len(doc["state"]["classes"])
    n_features = doc["state"]["forest"]["n_features"]
    doc["state"]["forest"] = _chain(MAX_TREE_DEPTH, n_features, outputs)
    loaded = saved.load(_write(tmp_path, doc), "learned")
    forest: ForestArrays = loaded.model
    # feature 0 below every threshold: left at the root, the first leaf; above all: the last
    x = np.zeros((2, n_features))
    x[1, 0] = 2.0
    assert forest._leaves(x)[:, 0].tolist() == [0, MAX_TREE_DEPTH]


def test_a_node_with_two_parents_is_refused(fitted, tmp_path):
    doc = saved.document(fitted, fitted_on=FITTED_ON)
    outputs = len(doc["state"]["classes"])
    n = 5  # root -> (1, 2); node 1 -> (3, 4); node 2 -> (3, 4): a diamond, not a tree
    left = np.array([1, 3, 3, LEAF, LEAF])
    right = np.array([2, 4, 4, LEAF, LEAF])
    forest = _chain(1, doc["state"]["forest"]["n_features"], outputs)
    forest["node_counts"] = _encoded(np.array([n]), "int64")
    forest["left"], forest["right"] = _encoded(left, "int64"), _encoded(right, "int64")
    forest["feature"] = _encoded(np.zeros(n, dtype=np.int64), "int64")
    forest["threshold"] = _encoded(np.zeros(n), "float64")
    forest["leaf_values"] = _encoded(np.full((2, outputs), 0.5), "float64")
    with pytest.raises(saved.ModelFileError, match="two parents"):
        saved.load(_write(tmp_path, _document(fitted, forest)), "learned")


def test_fitting_makes_no_tree_deeper_than_a_saved_one_may_be(fitted):
    forest = ForestArrays.from_sklearn(fitted.model)
    assert forest.check() is None
    estimators = fitted.model.named_steps["forest"].estimators_
    assert all(e.max_depth == MAX_TREE_DEPTH for e in estimators)


def _many(trees: int, n_features: int, outputs: int) -> dict:
    """``trees`` one-split trees (root -> two leaves), concatenated."""
    left = np.tile(np.array([1, LEAF, LEAF], dtype=np.int64), trees)
    right = np.tile(np.array([2, LEAF, LEAF], dtype=np.int64), trees)
    return {
        "n_features": n_features,
        "node_counts": _encoded(np.full(trees, 3), "int64"),
        "left": _encoded(left, "int64"),
        "right": _encoded(right, "int64"),
        "feature": _encoded(np.zeros(3 * trees, dtype=np.int64), "int64"),
        "threshold": _encoded(np.full(3 * trees, 0.5), "float64"),
        "leaf_values": _encoded(np.full((2 * trees, outputs), 1.0 / outputs), "float64"),
    }


def test_more_trees_than_fitting_makes_are_refused_and_as_many_load(fitted, tmp_path):
    """A window walks every tree: a forest of a million one-split trees would cost as the
    chain does. At most MAX_TREES (what fitting makes) load."""
    doc = saved.document(fitted, fitted_on=FITTED_ON)
    outputs = len(doc["state"]["classes"])
    n_features = doc["state"]["forest"]["n_features"]
    for trees in (MAX_TREES + 1, 1_000_000):
        doc["state"]["forest"] = _many(trees, n_features, outputs)
        with pytest.raises(saved.ModelFileError, match=f"{trees} trees; allowed at most") as info:
            saved.load(_write(tmp_path, doc), "learned")
        assert "\n" not in str(info.value)
    doc["state"]["forest"] = _many(MAX_TREES, n_features, outputs)
    assert saved.load(_write(tmp_path, doc), "learned").model.node_counts.size == MAX_TREES
    assert ForestArrays.from_sklearn(fitted.model).node_counts.size <= MAX_TREES
