"""Export and share: the design file and the stiffness table for download; the URL names of the
state's parameters and the link that holds them (a link holds the whole design and operating
point; a design parameter's name in it is its ``url_key`` in :mod:`core.parameters`)."""

from __future__ import annotations

import io

import numpy as np
import panel as pn
import param

from core.io.design_file import dumps_design
from core.io.export import export
from core.io.table import csv_text
from core.parameters import PARAMETERS

from .state import ExplorerState
from .units import to_si_amplitude

# label → (export format, file name)
TOOL_FORMATS = {
    "Nastran bulk data (PBUSH)": ("nastran", "bushing.bdf"),
    "Adams bushing file (.bus)": ("adams", "bushing.bus"),
    "Neutral table, every direction (CSV)": ("table", "bushing-directions.csv"),
    "Neutral table, every direction (JSON)": ("table-json", "bushing-directions.json"),
}


class ExportView(pn.viewable.Viewer):
    """Download the design file and the stiffness table; PNGs from each plot's toolbar."""

    def __init__(self, state: ExplorerState, **params):
        super().__init__(**params)
        self.state = state
        self.design_file = pn.widgets.FileDownload(
            callback=self._design_json, filename="bushing-design.json", label="Design file (JSON)",
            color="default", sizing_mode="stretch_width",
        )
        self.table_file = pn.widgets.FileDownload(
            callback=self._table_csv, filename="bushing-stiffness.csv", label="Stiffness table (CSV)",
            color="default", sizing_mode="stretch_width",
        )
        self.tool_format = pn.widgets.Select(
            label="For multibody and FE tools", options=list(TOOL_FORMATS), value="Nastran bulk data (PBUSH)",
            description="Every direction: over the sweep's frequency range (30 frequencies) at the operating "
            "amplitude and the Fletcher–Gent amplitudes; Adams: linearised at the operating point (docs/export.md).",
            sizing_mode="stretch_width")
        self.tool_file = pn.widgets.FileDownload(
            callback=self._tool_file, filename=TOOL_FORMATS[self.tool_format.value][1], label="Download",
            color="default", sizing_mode="stretch_width",
        )
        self.tool_format.param.watch(lambda e: setattr(self.tool_file, "filename", TOOL_FORMATS[e.new][1]), "value")

    def _design_json(self):
        return io.StringIO(dumps_design(self.state.design))

    def _table_csv(self):
        return io.StringIO(csv_text(self.state.stiffness_table()))

    def tool_text(self, label: str) -> str:
        """The export ``label`` (:data:`TOOL_FORMATS`) of the current design."""
        s = self.state
        fmt, _ = TOOL_FORMATS[label]
        x = float(to_si_amplitude(s.amplitude, s.design.mode))
        if fmt == "adams":
            return export(s.design, "adams", [s.frequency_hz], [x])
        freqs = np.geomspace(s.freq_min, s.freq_max, 30)
        amps = [x, *(float(to_si_amplitude(a, s.design.mode)) for a in s.fletcher_gent_amplitudes(s.design))]
        return export(s.design, "table" if fmt.startswith("table") else fmt, freqs, amps, as_json=fmt == "table-json")

    def _tool_file(self):
        return io.StringIO(self.tool_text(self.tool_format.value))

    def __panel__(self):
        return pn.Column(
            self.design_file,
            self.table_file,
            self.tool_format,
            self.tool_file,
            pn.pane.Markdown(
                "PNG: the save icon in each plot's toolbar. Share: the address bar holds the whole "
                "design; copy it.", sizing_mode="stretch_width", styles={"font-size": "0.9em"}),
            sizing_mode="stretch_width",
        )


URL_NAMES = {
    "mode": "mode",
    "finite_length": "finite",
    **{p.field: p.url_key for p in PARAMETERS},
    "amplitude": "amp",
    "frequency_hz": "f_Hz",
    "freq_min": "fmin_Hz",
    "freq_max": "fmax_Hz",
    "tolerance_text": "tol",
    "band_on": "bands",
}


def _unjudged(p: param.Parameter) -> param.Parameter:
    """A link's copy of the state's parameter ``p``: of its kind, but a number of any value or
    none (the state judges it)."""
    if isinstance(p, param.Selector):
        return param.Selector(objects=list(p.objects), default=p.default)
    if isinstance(p, (param.Boolean, param.String)):
        return type(p)(default=p.default)
    return param.Number(default=None, allow_None=True)


class ShareLink(param.Parameterized):
    """The design as the address bar shows it: the state's linked parameters (:data:`URL_NAMES`),
    untouched by validation (the state judges them). A link opened (or the browser's back
    button) applies at once; the state's changes reach the address bar after a pause, so a
    slider drag is one history entry and one URL write, not one per step."""


for _name in URL_NAMES:
    ShareLink.param.add_parameter(_name, _unjudged(ExplorerState.param[_name]))
