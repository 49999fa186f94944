"""python -m mfbd simulate|sweep ..."""
import sys


def main():
    commands = {"simulate": "mfbd.cli", "sweep": "mfbd.sweep"}
    if len(sys.argv) < 2 or sys.argv[1] not in commands:
        print("usage: python -m mfbd simulate|sweep ... (--help for each)", file=sys.stderr)
        return 2
    import importlib
    return importlib.import_module(commands[sys.argv[1]]).main(sys.argv[2:])


if __name__ == "__main__":
    sys.exit(main())
