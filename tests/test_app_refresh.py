"""One-way data flow (issue 26): every change reaches each visible view exactly once, whatever
it changes (a mode change moves the amplitude too; a preset sets everything); a change a view
does not draw, or an input that is not valid, does not redraw it; a hidden tab draws nothing
until it is shown, then once."""

import pytest

from app.main import App
from app.views import PlotView

# the App's views that draw the state → the index of their tab
VIEWS = {"plots": 0, "compare": 0, "slices": 1, "teaching": 2, "measured": 3, "card": 5, "whatif": 6}
# what each view draws, by the change's kind (True: the view must be drawn once; False: not at all)
CHANGES = {
    "amplitude": (lambda s: setattr(s, "amplitude", s.amplitude * 1.7),
                  {"plots": True, "compare": True, "slices": True, "teaching": True, "measured": False, "card": False,
                   "whatif": True}),
    "frequency": (lambda s: setattr(s, "frequency_hz", 23.0),
                  {"plots": True, "compare": True, "slices": True, "teaching": True, "measured": False, "card": True,
                   "whatif": True}),
    "typed shear modulus": (lambda s: setattr(s, "shear_modulus_mpa", 2.9), dict.fromkeys(VIEWS, True)),
    "mode (the amplitude follows)": (lambda s: setattr(s, "mode", "torsion"), dict.fromkeys(VIEWS, True)),
    "preset": (lambda s: setattr(s, "preset", "Table 1 bushing (torsion)"), dict.fromkeys(VIEWS, True)),
    "finite length": (lambda s: setattr(s, "finite_length", True), dict.fromkeys(VIEWS, True)),
    "an input that is not a number": (lambda s: setattr(s, "length_mm", None), dict.fromkeys(VIEWS, False)),
    "a pinned reference": (lambda s: s.pin_reference(),
                           {"plots": True, "compare": True, "slices": True, "teaching": True, "measured": False,
                            "card": True, "whatif": False}),
}


def counted(app: App) -> dict[str, list]:
    """Every plotting view built, its draws counted (view name → a list that grows by one per draw)."""
    counts = {}
    for name in VIEWS:
        view = getattr(app, name)
        assert isinstance(view, PlotView)
        calls = counts[name] = []
        draw = view._update
        view._update = lambda draw=draw, calls=calls: calls.append(1) or draw()
    return counts


@pytest.mark.parametrize("change", list(CHANGES))
@pytest.mark.parametrize("tab", sorted(set(VIEWS.values())))
def test_each_change_draws_the_visible_views_once_and_no_hidden_one(change, tab):
    app = App()
    counts = counted(app)
    app.tabs.active = tab
    for calls in counts.values():
        calls.clear()
    apply, draws = CHANGES[change]
    apply(app.state)
    assert {n: len(c) for n, c in counts.items()} == {n: int(draws[n] and t == tab) for n, t in VIEWS.items()}
    for name, other_tab in VIEWS.items():  # a hidden view catches up when shown: once, if it must
        if other_tab != tab:
            app.tabs.active = other_tab
            assert len(counts[name]) == int(draws[name]), name
            app.tabs.active = len(app.tabs) - 1  # About, then back: nothing new to draw
            app.tabs.active = other_tab
            assert len(counts[name]) == int(draws[name]), name
