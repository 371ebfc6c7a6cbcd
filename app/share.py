"""Export and share: the design file and the stiffness table for download; the URL names of the
state's parameters (a link holds the whole design and operating point)."""

from __future__ import annotations

import io

import panel as pn

from core.data import csv_text
from core.design import dumps_design

from .state import ExplorerState


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

    def _design_json(self):
        return io.StringIO(dumps_design(self.state.design))

    def _table_csv(self):
        return io.StringIO(csv_text(self.state.stiffness_table()))

    def __panel__(self):
        return pn.Column(
            self.design_file,
            self.table_file,
            pn.pane.Markdown(
                "PNG: the save icon in each plot's toolbar. Share: the address bar holds the whole "
                "design; copy it.", sizing_mode="stretch_width", styles={"font-size": "0.9em"}),
            sizing_mode="stretch_width",
        )


URL_NAMES = {
    "mode": "mode",
    "finite_length": "finite",
    "inner_radius_mm": "a_mm",
    "outer_radius_mm": "b_mm",
    "length_mm": "L_mm",
    "shear_modulus_mpa": "mu_MPa",
    "fractional_coefficient_mpa": "m_MPa",
    "fractional_order": "alpha",
    "friction_stress_max_kpa": "sigma_kPa",
    "friction_strain_half": "eps_half",
    "amplitude": "amp",
    "frequency_hz": "f_Hz",
    "freq_min": "fmin_Hz",
    "freq_max": "fmax_Hz",
}
