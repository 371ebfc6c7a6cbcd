"""A document's set of models kept up to date by the models a change added, not by a walk of
the whole document (issue #27, item 16).

Bokeh keeps each document's set of models (``Document.models``, a ``DocumentModelManager``)
by walking every model reachable from the document's roots (``recompute``) whenever a property
that refers to models changes (``Model.trigger`` calls ``invalidate``), or once when the last
freeze ends. :func:`frozen_models` freezes the models for a whole change of the app and walks
only if the change asked for it; a change that only *adds* models (a plot put into its empty
place in the page, a glyph added to a plot) is then settled without the walk: the models
reachable from the values it set that the document does not hold yet are collected
(Bokeh's own ``collect_filtered_models``, not descending into models it holds: those already
hold what they refer to) and attached as ``recompute`` attaches them. A change that drops a
reference (a model may leave the document) takes Bokeh's whole walk, as before.

Measured (``benchmarks/diagnosis_report_cpu.py [--walk]``: 150 points loaded in the diagnosis
tab, whose seven report plots are then made ready, each in its own change): each walk of the
page took 35–50 ms (750 models); the server's CPU for the data loaded fell from 744–745 ms with
the walks to 561–599 ms.

Private internals of Bokeh 3.9 used here: the manager's ``_models``, ``_models_by_name``,
``_new_models``, ``_freeze_count``, ``_push_freeze`` and ``Model._attach_document``, and that
``Model.trigger`` calls ``document.models.invalidate()`` for a change of a reference.
``tests/test_model_graph.py`` compares the result with Bokeh's own walk after additions,
removals and replacements, and fails if an internal is gone.
"""

from __future__ import annotations

import contextlib

from bokeh.model import Model
from bokeh.model.util import collect_filtered_models, visit_value_and_its_immediate_references

_CHANGES = "_bushing_reference_changes"  # the manager's attribute: the block's log, while frozen


def track_reference_changes() -> None:
    """``Model.trigger`` wrapped, once per process: a change of a reference of a model in a
    document frozen by :func:`frozen_models` is logged there (its old and new values) when Bokeh
    asks for a walk of it. Elsewhere the wrapper only looks for the log, and Bokeh's trigger runs
    as it was."""
    original = Model.trigger
    if getattr(original, "logged_by_bushing", False):
        return

    def trigger(self, attr, old, new, hint=None, setter=None):
        doc = self._document
        log = getattr(doc.models, _CHANGES, None) if doc is not None else None
        if log is None:
            return original(self, attr, old, new, hint=hint, setter=setter)
        asked = log.asked
        original(self, attr, old, new, hint=hint, setter=setter)
        if log.asked != asked:  # this change (or one its callbacks made) asked for a walk
            log.append((old, new))

    trigger.logged_by_bushing, trigger.original = True, original
    Model.trigger = trigger


def tracking() -> bool:
    """Whether :func:`track_reference_changes` is in place."""
    return getattr(Model.trigger, "logged_by_bushing", False)


class _Log(list):
    """The (old, new) values of the references changed in one frozen block; ``asked``: how many
    times Bokeh asked for a walk meanwhile."""

    asked = 0


def _ids(value) -> set:
    found: set = set()
    visit_value_and_its_immediate_references(value, lambda model: found.add(model.id))
    return found


def attach_added(models, changes) -> bool:
    """Settle the document's set of models after ``changes`` (old, new values of the references
    changed) if they only added references: the new models attached as Bokeh's ``recompute``
    attaches them. False, with nothing done, if a change dropped a reference."""
    if any(_ids(old) - _ids(new) for old, new in changes):
        return False
    document = models._document()
    if document is None:
        return True
    known = models._models
    for model in collect_filtered_models(lambda m: m.id in known, *(new for _, new in changes)):
        known[model.id] = model
        if model.name is not None:
            models._models_by_name.add_value(model.name, model)
        model._attach_document(document)
        models._new_models.add(model)
    return True


def _roots(doc) -> list | None:
    """The document's roots; None once it is destroyed (Bokeh's ``Document.destroy`` deletes them)."""
    try:
        return list(doc.roots)
    except AttributeError:
        return None


@contextlib.contextmanager
def frozen_models(doc):
    """``doc.models`` frozen while the block runs; at its end, if the model graph changed in it,
    the new models attached (:func:`attach_added`) or, if a reference was dropped, a root added or
    removed, or the changes were not logged (:func:`track_reference_changes` not installed),
    Bokeh's whole walk. Nested inside another freeze, an ordinary freeze."""
    models = doc.models
    if models._freeze_count:
        with models.freeze():
            yield
        return
    log = _Log()
    roots = _roots(doc)

    def invalidate():
        log.asked += 1

    models.invalidate = invalidate  # shadows the method for this block
    setattr(models, _CHANGES, log)
    models._push_freeze()
    try:
        yield
    finally:
        del models.invalidate
        delattr(models, _CHANGES)
        models._freeze_count -= 1
        now = _roots(doc)
        # a root added or removed: no reference change says so, the walk finds its models; a
        # document destroyed (its page's session discarded) keeps nothing up to date
        if models._freeze_count == 0 and now is not None and (
                now != roots or (log.asked and not (tracking() and attach_added(models, log)))):
            models.recompute()
