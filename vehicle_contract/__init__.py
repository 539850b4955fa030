"""vehicle_contract package."""
