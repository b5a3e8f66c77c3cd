//! Run directories (formats.md): measurements.csv, bearings.csv, truth.json.
