"""Configuration: the field mechanism, TOML campaign files, and the campaign tables."""
