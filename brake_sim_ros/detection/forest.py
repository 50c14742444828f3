"""A fitted scikit-learn random forest as plain arrays, and its prediction from them.

Why arrays and not pickle: a saved detector (:mod:`.saved`) must never execute a file, and
unpickling runs whatever the file names. Why not a refit from stored training features
(14 040 windows x 80 features for the reference campaign: about 12 MB against the trees'
61 MB): the refitted forest equals the saved one only if the loading machine's
scikit-learn builds the same trees from the same seed (another version may not), and
every load would pay the refit (seconds to minutes) that saving is meant to spare. The
trees' own arrays (scikit-learn's ``tree_`` attributes: children, split feature,
threshold, and the leaves' values) are exact by construction and load at once, and a
hostile file can do no more than give wrong numbers: every index is checked
(:meth:`ForestArrays.check`) before use, and numpy indexing is bounds-checked.

Prediction repeats scikit-learn's (1.x, ``sklearn/tree/_tree.pyx`` and
``sklearn/ensemble/_forest.py``) operation for operation, so it is bit for bit the same:
the features after the pipeline's constant imputer (NaN -> 0), cast to float32 as the trees
read them; at each split ``x[feature] <= threshold`` (float32 value against the float64
threshold) goes left; a tree's output is its leaf's value row (class fractions or the
regression target); the forest adds the trees' outputs one at a time in tree order to
zeros and divides by the number of trees. A test checks it against scikit-learn's own on a
real dataset (``tests/detection/test_saved.py``).
"""

from __future__ import annotations

import functools
from dataclasses import dataclass

import numpy as np

LEAF = -1  # scikit-learn's TREE_LEAF: a node without children
# the deepest tree fitting makes (learned.py gives it as max_depth; real trees on the
# reference campaign are far shallower) and so the deepest a saved one may hold: a window's
# prediction walks at most this many levels, however the file was made
MAX_TREE_DEPTH = 128
# the most trees one fitted forest holds (learned.py's classifier: N_TREES = 100; its
# severity regressors have fewer): a window's prediction walks at most this many trees
MAX_TREES = 100


@dataclass(frozen=True)
class ForestArrays:
    """The trees of one fitted forest, concatenated in tree order.

    Attributes:
        n_features: features per row the forest reads.
        node_counts: nodes per tree, shape (n_trees,), int64.
        left, right: each node's children as indices within its own tree (:data:`LEAF` for
            a leaf: both), shape (n_nodes,), int64.
        feature: each split node's feature index (ignored at a leaf), shape (n_nodes,).
        threshold: each split node's threshold (ignored at a leaf), shape (n_nodes,),
            float64.
        leaf_values: one row per leaf, in node order: the classes' fractions in the leaf
            (a classifier, in the order of its classes) or the target's mean there (a
            regressor, one column), shape (n_leaves, n_outputs), float64.
    """

    n_features: int
    node_counts: np.ndarray
    left: np.ndarray
    right: np.ndarray
    feature: np.ndarray
    threshold: np.ndarray
    leaf_values: np.ndarray

    @classmethod
    def from_sklearn(cls, pipeline) -> ForestArrays:
        """The arrays of a fitted ``Pipeline([("impute", SimpleImputer(constant 0)),
        ("forest", RandomForest...)])`` (:mod:`.learned`'s)."""
        forest = pipeline.named_steps["forest"]
        trees = [e.tree_ for e in forest.estimators_]
        leaf = [t.children_left == LEAF for t in trees]
        values = [t.value[:, 0, :][is_leaf] for t, is_leaf in zip(trees, leaf, strict=True)]
        return cls(
            n_features=int(forest.n_features_in_),
            node_counts=np.array([t.node_count for t in trees], dtype=np.int64),
            left=np.concatenate([t.children_left for t in trees]).astype(np.int64),
            right=np.concatenate([t.children_right for t in trees]).astype(np.int64),
            feature=np.concatenate([t.feature for t in trees]).astype(np.int64),
            threshold=np.concatenate([t.threshold for t in trees]).astype(np.float64),
            leaf_values=np.concatenate(values).astype(np.float64),
        )

    def check(self) -> str | None:
        """What is wrong with the arrays (one line, naming the array), or None: every tree
        is a tree (a split's children come after it in its own tree, so a walk ends), every
        split reads a feature that exists, every value is finite."""
        counts, n = self.node_counts, self.left.size
        if counts.ndim != 1 or counts.size == 0 or np.any(counts < 1):
            return "node_counts: allowed one count >= 1 per tree"
        if counts.size > MAX_TREES:
            return f"{counts.size} trees; allowed at most {MAX_TREES}, the most fitting makes"
        if int(counts.sum()) != n:
            return f"node_counts: they add to {int(counts.sum())}, the trees hold {n} nodes"
        for name in ("right", "feature", "threshold"):
            if getattr(self, name).shape != (n,):
                return f"{name}: allowed one entry per node ({n})"
        local = np.arange(n) - np.repeat(np.cumsum(counts) - counts, counts)
        size = np.repeat(counts, counts)
        leaf = self.left == LEAF
        if np.any(leaf != (self.right == LEAF)):
            return "left, right: a node with one child; allowed two children or none"
        split = ~leaf
        for name, child in (("left", self.left), ("right", self.right)):
            if np.any(split & ((child <= local) | (child >= size))):
                return f"{name}: a child outside its tree or not after its parent"
        offset = np.arange(n) - local  # each node's tree's first node
        both = np.concatenate([split, split])
        children = np.concatenate([self.left + offset, self.right + offset])[both]
        if children.size != n - counts.size or np.bincount(children, minlength=n).max() > 1:
            return "left, right: a node with two parents, or one no split leads to"
        if self._depth() > MAX_TREE_DEPTH:
            return f"a tree deeper than {MAX_TREE_DEPTH} levels; fitting makes none deeper"
        if np.any(split & ((self.feature < 0) | (self.feature >= self.n_features))):
            return f"feature: allowed 0 to {self.n_features - 1} at a split"
        if not np.all(np.isfinite(self.threshold[split])):
            return "threshold: allowed finite numbers at a split"
        values = self.leaf_values
        if values.ndim != 2 or values.shape[0] != int(leaf.sum()) or values.shape[1] < 1:
            return f"leaf_values: allowed one row per leaf ({int(leaf.sum())})"
        if not np.all(np.isfinite(values)):
            return "leaf_values: allowed finite numbers"
        return None

    def _depth(self) -> int:
        """The deepest tree's depth (a lone leaf: 0), counted up to one past
        :data:`MAX_TREE_DEPTH` (the trees are checked to be trees first)."""
        starts, left, right, _, _ = self._walk
        frontier = starts
        for depth in range(MAX_TREE_DEPTH + 1):
            frontier = frontier[left[frontier] >= 0]
            if frontier.size == 0:
                return depth
            frontier = np.concatenate([left[frontier], right[frontier]])
        return MAX_TREE_DEPTH + 1

    @functools.cached_property
    def _walk(self) -> tuple[np.ndarray, ...]:
        """Each tree's root, the children as indices into all nodes (-1 at a leaf), the
        split features (0 at a leaf), each node's leaf row: computed once, not per call."""
        starts = np.cumsum(self.node_counts) - self.node_counts
        offset = np.repeat(starts, self.node_counts)
        leaf = self.left == LEAF
        left = np.where(leaf, -1, self.left + offset)
        right = np.where(leaf, -1, self.right + offset)
        feature = np.where(leaf, 0, self.feature)
        return starts, left, right, feature, np.cumsum(leaf) - 1

    def _leaves(self, X: np.ndarray) -> np.ndarray:
        """The leaf row (into :attr:`leaf_values`) each row of ``X`` reaches in each tree,
        shape (n_rows, n_trees)."""
        X = np.asarray(X, dtype=np.float64)
        if X.ndim != 2 or X.shape[1] != self.n_features:
            raise ValueError(f"features of shape {X.shape}: allowed (n, {self.n_features})")
        X = np.where(np.isnan(X), 0.0, X).astype(np.float32)  # the imputer, then the trees
        if not np.all(np.isfinite(X)):
            raise ValueError("features: an infinite value, or one too large for float32")
        starts, left, right, feature, leaf_row = self._walk
        rows = np.arange(X.shape[0])[:, None]
        node = np.broadcast_to(starts, (X.shape[0], starts.size)).copy()
        for _ in range(MAX_TREE_DEPTH + 1):  # each step goes deeper: it ends (check())
            at_split = left[node] >= 0
            if not at_split.any():
                break
            go_left = X[rows, feature[node]].astype(np.float64) <= self.threshold[node]
            node = np.where(at_split, np.where(go_left, left[node], right[node]), node)
        return leaf_row[node]

    def _mean(self, X: np.ndarray) -> np.ndarray:
        """The trees' leaf values summed one tree at a time in order, over the tree count
        (as scikit-learn's forests), shape (n_rows, n_outputs)."""
        leaves = self._leaves(X)
        total = np.zeros((leaves.shape[0], self.leaf_values.shape[1]), dtype=np.float64)
        for t in range(leaves.shape[1]):
            total += self.leaf_values[leaves[:, t]]
        total /= leaves.shape[1]
        return total

    def predict_proba(self, X: np.ndarray) -> np.ndarray:
        """A classifier's class probabilities, shape (n_rows, n_classes)."""
        return self._mean(X)

    def predict(self, X: np.ndarray) -> np.ndarray:
        """A regressor's estimate, shape (n_rows,)."""
        return self._mean(X)[:, 0]
