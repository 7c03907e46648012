"""The mods bundled with sandmod: one TOML file per element pack (data only)."""
