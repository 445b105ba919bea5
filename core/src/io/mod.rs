//! Reading and writing the toolkit's files (placeholder, being written).
