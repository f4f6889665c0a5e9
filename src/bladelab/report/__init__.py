"""HTML reports: composable sections, embedded figures, tables also written as CSV.

Build a :class:`Report`, add sections from any workflow (characterise, predict, design), and
:meth:`Report.write` a self-contained ``index.html`` that opens offline::

    from bladelab.report import Report, figures
    report = Report("Blade characterisation", settings=config, seed=seed)
    report.add_section("GRF", figures=[figures.time_series_bands(measured, simulated)])
    report.write(study_dir / "report")
"""

from bladelab.report import figures, tables
from bladelab.report.builder import EmbeddedFigure, Report, ReportTable, Section
from bladelab.report.figures import (
    compressive_stiffness_curves,
    hysteresis_loops,
    parameter_bars,
    time_series_bands,
)
from bladelab.report.tables import (
    mean_curve_nrmse,
    nrmse_pct,
    nrmse_table,
    parameter_summary_display,
    stats_display,
    trial_nrmse,
)

__all__ = [
    "EmbeddedFigure",
    "Report",
    "ReportTable",
    "Section",
    "figures",
    "tables",
    "compressive_stiffness_curves",
    "hysteresis_loops",
    "parameter_bars",
    "time_series_bands",
    "mean_curve_nrmse",
    "nrmse_pct",
    "nrmse_table",
    "parameter_summary_display",
    "stats_display",
    "trial_nrmse",
]
