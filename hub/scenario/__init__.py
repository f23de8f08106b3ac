"""Scenarios: the checked model, YAML read with its lines, the checker and expectations."""
