"""Assembly of the mortar operators D, M and κ."""
