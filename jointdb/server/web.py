"""Web catalogue (placeholder until the pages are added)."""


def mount(app) -> None:
    return None
