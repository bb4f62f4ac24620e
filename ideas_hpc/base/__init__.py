"""The ground floor: helpers every layer may use, importing nothing above them (errors, units,
constants, seeds, progress, fields, instrument, spice)."""
