"""Tables of runs for analysis and learning: Parquet files of samples and sensor channels."""
