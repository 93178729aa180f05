"""HMM-based trajectory synthesis (the ``hmm`` row of Taylor et al. 2017): see :mod:`.model`."""

from .mlpg import WINDOWS, dynamic_features, mlpg, window_matrix
from .model import HMMSynthesizer, durations_for_length, merge_silences, viterbi_em, viterbi_segments
from .tree import context_questions, grow_tree, tree_leaves

__all__ = [
    "HMMSynthesizer",
    "mlpg",
    "dynamic_features",
    "window_matrix",
    "WINDOWS",
    "viterbi_em",
    "viterbi_segments",
    "durations_for_length",
    "merge_silences",
    "context_questions",
    "grow_tree",
    "tree_leaves",
]
