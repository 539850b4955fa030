"""tests.vehicle_contract package."""
