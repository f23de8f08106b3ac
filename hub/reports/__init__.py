"""Reports: run scenarios, measure them and write markdown with plots (`python -m hub report NAME`)."""

REPORTS = {"paper": "hub.reports.paper_report:write"}
