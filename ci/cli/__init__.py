"""The overtake command, one module per command group; each parses, calls the layers below and prints."""
