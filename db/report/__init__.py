"""The end-of-line report's queries: sections, charts, trends, split, alerts,
what-if, station health and the runs export, over the store's tables and the roll-ups."""
