"""Everything that touches a file: bundles, instrument and vendor formats, datasheets, confined
atomic writes."""
