"""Evaluation: policies run over suites of cases (`runner`, frozen or learning online), the
paper's metrics from their run logs, intervals over seeds, and the tables and reports."""
