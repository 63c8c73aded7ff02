"""Assembly of the mortar operators D, M and κ from the integration points (assemble), deterministic CSR (sparse)."""
