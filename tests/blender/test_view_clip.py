"""The clip range a row click moves comes back (issue 35, docs/blender.md "Results").

A click on a 1 cm model's section stands the view 12 section radii away, inside Blender's
default near clip (0.01): the click lowers it.  The user's range must come back when the view
leaves the section (Home, View Selected, a pan away, zooming out), at the next click that does
not need it, and when the add-on is disabled; an orbit or a small pan around the section keeps
it; a range the user sets meanwhile stays.  Run on the factory startup's real 3D viewports
(background Blender has no window to click in: ``frame`` is given the Layout screen's areas and
the timer's ``viewclip.check`` is called as the timer would)."""

import bpy
import numpy as np
import pytest
from conftest import empty_scene
from osteon_blender import viewclip
from osteon_blender.ops import select_bone as sb

USER = (0.01, 1000.0)            # Blender's default clip range
TINY = {"centre": (0.002, 0.001, 0.004), "radius": 1.6e-4, "size": 0.012}   # a 1.2 cm dog's tail


@pytest.fixture
def view(addon):
    empty_scene()
    areas = [a for a in bpy.data.screens["Layout"].areas if a.type == "VIEW_3D"]
    assert areas, "the factory Layout screen has a 3D viewport"
    space = areas[0].spaces.active
    assert (space.clip_start, space.clip_end) == pytest.approx(USER)
    yield areas, space
    viewclip.held_spaces().clear()


def _click(areas, where=TINY):
    return sb.frame(bpy.context, where["centre"], where["radius"], None, where["size"],
                    areas=areas)


def _clip(space):
    return space.clip_start, space.clip_end


def test_a_click_on_a_tiny_section_lowers_the_near_clip_and_holds_the_users(view):
    areas, space = view
    assert _click(areas) == len(areas)
    d = sb.FRAME_RADII * TINY["radius"]
    assert space.region_3d.view_distance == pytest.approx(d)
    start, end = _clip(space)
    assert start <= 0.25 * d and end >= d + 2 * TINY["size"]    # the section is inside the range
    assert end / start == pytest.approx(viewclip.CLIP_RATIO, rel=1e-3)
    assert viewclip.held_spaces()[space.as_pointer()]["user"] == pytest.approx(USER)
    # an orbit and a small pan around the section keep it
    space.region_3d.view_rotation = (0.7071, 0.7071, 0.0, 0.0)
    space.region_3d.view_location = np.asarray(TINY["centre"]) + [0.2 * d, 0.0, 0.0]
    viewclip.check()
    assert _clip(space) == pytest.approx((start, end))


def test_the_users_range_comes_back_when_the_view_leaves_the_section(view):
    areas, space = view
    _click(areas)
    space.region_3d.view_location = (1.0, 2.0, 0.5)          # Home / View Selected elsewhere
    viewclip.check()
    assert _clip(space) == pytest.approx(USER) and not viewclip.held_spaces()


def test_the_users_range_comes_back_when_zoomed_out(view):
    areas, space = view
    _click(areas)
    space.region_3d.view_distance = 4.0 * USER[0]           # the user's near clip shows it again
    viewclip.check()
    assert _clip(space) == pytest.approx(USER)


def test_the_next_click_starts_from_the_users_range(view):
    areas, space = view
    _click(areas)
    _click(areas, {"centre": (0.0, 0.0, 0.0), "radius": 0.5, "size": 2.0})   # a 2 m model's limb
    assert _clip(space) == pytest.approx(USER) and not viewclip.held_spaces()
    _click(areas)
    first = _clip(space)
    _click(areas, dict(TINY, radius=2 * TINY["radius"]))    # another tiny section: from USER
    d = sb.FRAME_RADII * 2 * TINY["radius"]
    assert _clip(space) == pytest.approx((0.05 * d, 0.05 * d * viewclip.CLIP_RATIO), rel=1e-5)
    assert _clip(space) != pytest.approx(first)
    assert viewclip.held_spaces()[space.as_pointer()]["user"] == pytest.approx(USER)


def test_a_range_the_user_sets_meanwhile_stays(view):
    areas, space = view
    _click(areas)
    space.clip_start = 1e-5                                   # the user's own choice
    viewclip.check()
    assert not viewclip.held_spaces()
    space.region_3d.view_location = (1.0, 2.0, 0.5)
    viewclip.check()
    assert space.clip_start == pytest.approx(1e-5)


def test_disabling_the_addon_puts_the_users_range_back(view):
    areas, space = view
    _click(areas)
    assert _clip(space) != pytest.approx(USER)
    viewclip.unregister()
    try:
        assert _clip(space) == pytest.approx(USER) and not viewclip.held_spaces()
    finally:
        viewclip.register()


def test_clip_rules_without_blender():
    """The rule itself: the range moves only where it would cut the view, far / near kept."""
    assert viewclip.clip_for_view(0.01, 1000.0, 10.0, 5.0) == (0.01, 1000.0)
    start, end = viewclip.clip_for_view(0.01, 1000.0, 0.002, 0.01)
    assert start == pytest.approx(1e-4) and end == pytest.approx(10.0)
    assert viewclip.clip_for_view(0.01, 100.0, 500.0, 80.0)[1] == pytest.approx(820.0)
    held = {"user": (0.01, 1000.0), "centre": np.zeros(3), "distance": 0.002, "size": 0.01}
    assert not viewclip.left_section(held, (0.0005, 0.0, 0.0), 0.002)
    assert viewclip.left_section(held, (0.0015, 0.0, 0.0), 0.002)
    assert viewclip.left_section(held, (0.0, 0.0, 0.0), 0.05)
