"""Export: the design file, the stiffness table and the multibody and FE tools' files, for
download."""

from __future__ import annotations

import io

import numpy as np
import panel as pn

from core.bushing import stiffness
from core.io.design_file import dumps_design
from core.io.export import export
from core.io.table import csv_text
from core.whatif.tolerance import band, band_columns

from .bands import band_tolerances, banded
from .curves import amplitude_grid, fletcher_gent_amplitudes
from .fit_state import FitState
from .inputs import copy_link_button
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

    def __init__(self, state: ExplorerState, fit: FitState, **params):
        super().__init__(**params)
        self.state, self.fit = state, fit
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
        self.copy_link = copy_link_button()
        self.tool_format.param.watch(lambda e: setattr(self.tool_file, "filename", TOOL_FORMATS[e.new][1]), "value")

    def _design_json(self):
        return io.StringIO(dumps_design(self.state.design))

    def _table_csv(self):
        return io.StringIO(csv_text(self.stiffness_table()))

    def stiffness_table(self, n_freq: int = 25, n_amp: int = 25) -> dict:
        """The docs/files.md stiffness table over the sweeps' frequency range and the
        Fletcher–Gent amplitude range (SI units); with the tolerance bands on, their percentile
        columns too (those of ``bushing stiffness --tolerance``)."""
        s = self.state
        f, x = np.linspace(*s.freq_range, n_freq), to_si_amplitude(amplitude_grid(s.design, n_amp), s.design.mode)
        table = stiffness(s.design, f, x).table()
        tolerances = band_tolerances(**s.band_inputs(), fit_result=self.fit.fit_result)
        columns, _reason = banded(tolerances, lambda tol: band_columns(band(s.design, f[None, :], np.asarray(x)[:, None], tol)))
        return {**table, **(columns or {})}

    def tool_text(self, label: str) -> str:
        """The export ``label`` (:data:`TOOL_FORMATS`) of the current design."""
        s = self.state
        fmt, _ = TOOL_FORMATS[label]
        x = float(to_si_amplitude(s.amplitude, s.design.mode))
        if fmt == "adams":
            return export(s.design, "adams", [s.frequency_hz], [x])
        freqs = np.geomspace(s.freq_min, s.freq_max, 30)
        amps = [x, *(float(to_si_amplitude(a, s.design.mode)) for a in fletcher_gent_amplitudes(s.design))]
        return export(s.design, "table" if fmt.startswith("table") else fmt, freqs, amps, as_json=fmt == "table-json")

    def _tool_file(self):
        return io.StringIO(self.tool_text(self.tool_format.value))

    def __panel__(self):
        return pn.Column(
            self.design_file,
            self.table_file,
            self.tool_format,
            self.tool_file,
            self.copy_link,
            pn.pane.Markdown(
                "Share: the link (the address bar) holds what the page shows: the design with its "
                "effects, the pinned reference, the operating point and the bands. The design file "
                "opens again with **Open a design file**, just above. PNG: the save icon in each plot's toolbar.",
                sizing_mode="stretch_width", styles={"font-size": "0.9em"}),
            sizing_mode="stretch_width",
        )

