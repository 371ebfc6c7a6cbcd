"""What the app changes outside its own objects: axis ranges only on clones of its dimensions,
and library internals (app.patches) only once ``create_app`` installs them."""


import numpy as np
import pytest

from app.main import App


@pytest.fixture
def app():
    return App()


def ranges(overlay):
    return [(d.name, tuple(d.range)) for el in overlay for d in el.dimensions()]


@pytest.mark.parametrize("view, plot", [("teaching", "real"), ("teaching", "loop"), ("slices", "magnitude"),
                                        ("card", "translation")])
def test_a_view_keeps_the_axes_of_what_it_drew_before(app, view, plot):
    """A tab redrawn for a very different design draws on new ranges; the overlay it showed before
    keeps its own (the Fletcher–Gent tab, the slices, the card)."""
    v = app.view(view)
    v.show(True)
    old = v.frame(plot)
    before = ranges(old)
    app.state.friction_strain_half *= 100  # the amplitude axis moves two decades
    app.state.shear_modulus_mpa *= 10
    app.state.outer_radius_mm *= 1.5  # and the drive of a strain (the card)
    assert v.frame(plot) is not old
    assert ranges(old) == before
    assert plot == "loop" or ranges(v.frame(plot)) != before
    assert all(tuple(d.range) == (None, None) for d in v.dims.values())


def test_the_fits_residuals_draw_on_their_own_range(app):
    from core.synthetic import paper_b_example

    m = app.view("measured")
    m.show(True)
    data, _ = paper_b_example(app.state.design)
    app.state.measured = data
    old = m.residuals.current[0]
    before = ranges(old)
    app.state.shear_modulus_mpa *= 3  # far from the data: residuals of another size
    assert ranges(old) == before and ranges(m.residuals.current[0]) != before
    assert np.isfinite(before[1][1]).all()
