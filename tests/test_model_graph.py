"""app.patches.model_graph: after any change made in one frozen block, the document holds the
models Bokeh's own walk finds (every model reachable from its roots, attached to it, by id and by
name), and it walks only when the change dropped a reference or changed the roots."""

from __future__ import annotations

import pytest
from bokeh.document import Document
from bokeh.models import Column, ColumnDataSource, DataTable, Div, Row, TableColumn
from hypothesis import given, settings
from hypothesis import strategies as st

from app.patches.model_graph import frozen_models, track_reference_changes, tracking


@pytest.fixture(autouse=True, scope="module")
def tracked():
    track_reference_changes()
    assert tracking()


def reachable(doc) -> dict:
    """Bokeh's own walk: every model reachable from the roots, by id."""
    return {m.id: m for root in doc.roots for m in root.references()}


def assert_settled(doc):
    found = reachable(doc)
    assert set(doc.models._models) == set(found)
    assert all(m.document is doc for m in found.values())
    for m in found.values():
        if m.name is not None:
            assert m in doc.models.get_all_by_name(m.name)


def counted_walks(doc) -> list:
    walks = []
    recompute = doc.models.recompute
    doc.models.recompute = lambda: walks.append(1) or recompute()
    return walks


def page() -> tuple[Document, Column, ColumnDataSource]:
    shared = ColumnDataSource(data={"x": [1, 2]}, name="shared")
    root = Column(children=[Div(text="a", name="first"), Row(children=[Column(children=[])])])
    doc = Document()
    doc.add_root(root)
    return doc, root, shared


def test_a_plot_put_into_its_empty_place_is_attached_without_a_walk():
    doc, root, shared = page()
    slot = root.children[1].children[0]
    walks = counted_walks(doc)
    with frozen_models(doc):
        table = DataTable(source=shared, columns=[TableColumn(field="x")], name="table")
        slot.children = [Column(children=[table, Div(text="b")])]
        table.source.data = {"x": [3, 4]}  # data only
    assert walks == []
    assert doc.get_model_by_id(shared.id) is shared and doc.get_model_by_name("table") is table
    assert shared in doc.models._new_models
    assert_settled(doc)


def test_a_dropped_reference_takes_bokehs_walk():
    doc, root, _ = page()
    first = root.children[0]
    walks = counted_walks(doc)
    with frozen_models(doc):
        root.children = [root.children[1]]
    assert walks == [1]
    assert first.document is None and doc.get_model_by_id(first.id) is None
    assert_settled(doc)


def test_a_root_added_takes_bokehs_walk():
    doc, _, shared = page()
    walks = counted_walks(doc)
    with frozen_models(doc):
        doc.add_root(Column(children=[DataTable(source=shared)]))
    assert walks == [1] and shared.document is doc
    assert_settled(doc)


def test_a_change_of_numbers_only_walks_nothing():
    doc, root, _ = page()
    walks = counted_walks(doc)
    with frozen_models(doc):
        root.children[0].text = "changed"
        root.width = 300
    assert walks == []
    assert_settled(doc)


def test_a_destroyed_document_is_left_alone():
    """A page's session discarded (its document destroyed) while work still writes to it: the
    block runs and ends without an error, and walks nothing."""
    doc, root, _ = page()
    child = root.children[0]
    session = lambda _event: None  # what a server session registers, and destroy removes
    doc.on_change(session)
    doc.destroy(session)
    with frozen_models(doc):
        child.text = "late"
        root.children = [*root.children, Div(text="late")]


# any sequence of additions, removals, moves and replacements in one block
OPERATIONS = st.lists(st.tuples(st.sampled_from(["add", "nest", "share", "drop", "move", "replace", "name"]),
                                st.integers(0, 1000)), max_size=12)


@settings(max_examples=60, deadline=None)
@given(OPERATIONS, st.booleans())
def test_any_change_leaves_the_models_bokehs_walk_finds(operations, outside_first):
    doc, root, shared = page()
    if outside_first:  # a model made and changed before it joins the document
        loose = Column(children=[Div(text="loose")])
        loose.children = [*loose.children, DataTable(source=shared)]
    with frozen_models(doc):
        for op, n in operations:
            layouts = [m for m in reachable(doc).values() if isinstance(m, (Column, Row))]
            target = layouts[n % len(layouts)]
            if op == "add":
                target.children = [*target.children, Div(text=str(n))]
            elif op == "nest":
                target.children = [*target.children, Row(children=[Column(children=[Div(text="deep")])])]
            elif op == "share":
                target.children = [*target.children, DataTable(source=shared)]
            elif op == "drop" and target.children:
                target.children = target.children[:-1]
            elif op == "move" and target.children and target is not root:
                moved = target.children[-1]
                target.children = target.children[:-1]
                root.children = [*root.children, moved]
            elif op == "replace":
                target.children = [Div(text="only")]
            elif op == "name":
                target.name = f"layout {n}"
        if outside_first:
            root.children = [*root.children, loose]
    assert_settled(doc)
