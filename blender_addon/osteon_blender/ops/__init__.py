"""Operators: osteon.analyze, osteon.correct, osteon.reset, osteon.apply, osteon.select_bone,
osteon.next_weak_bone, osteon.make_skeleton, osteon.select_loose_pieces, osteon.export_slicer."""

from .analyze import OSTEON_OT_analyze
from .apply import OSTEON_OT_apply
from .correct import OSTEON_OT_correct
from .loose import OSTEON_OT_select_loose_pieces
from .orientation import classes as _orientation_classes
from .reset import OSTEON_OT_reset
from .select_bone import OSTEON_OT_next_weak_bone, OSTEON_OT_select_bone
from .skeleton import OSTEON_OT_make_skeleton
from .slicer_export import classes as _slicer_classes

classes = (OSTEON_OT_analyze, OSTEON_OT_correct, OSTEON_OT_reset, OSTEON_OT_apply,
           OSTEON_OT_select_bone, OSTEON_OT_next_weak_bone, OSTEON_OT_make_skeleton,
           OSTEON_OT_select_loose_pieces) + _orientation_classes + _slicer_classes
