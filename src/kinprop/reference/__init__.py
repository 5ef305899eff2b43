"""The paper's numerical examples as reference data, and their reproduction."""

from kinprop.reference.paper import TABLES, Comparison, PaperTable, compare_table, reproduce

__all__ = ["TABLES", "Comparison", "PaperTable", "compare_table", "reproduce"]
