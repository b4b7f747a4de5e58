"""Result files: datasets and estimates as parquet and their columns, the plain-text interchange
for programs in any language, and tables as CSV, Markdown and HTML."""
