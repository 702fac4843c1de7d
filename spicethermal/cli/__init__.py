"""The command line: argparse only (parse, call the library, print)."""
