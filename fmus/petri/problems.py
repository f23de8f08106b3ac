"""NetError and the collector behind it: every problem of a net file, with its line, raised once."""

import difflib


class NetError(Exception):
    """Every problem found in net descriptions, one per line, each as 'file:line: cause'."""

    def __init__(self, problems):
        self.problems = list(problems)
        super().__init__("\n".join(self.problems))


class Problems:
    """The problems of one net file, collected so that a user sees all of them at once."""

    def __init__(self, path):
        self.path = path
        self._found = []

    def add(self, line, text):
        self._found.append((line, text))

    def __bool__(self):
        return bool(self._found)

    def messages(self):
        # Sorted by line (stable, so one line's problems keep the order they were found in).
        return [f"{self.path}:{line}: {text}" for line, text in sorted(self._found, key=lambda item: item[0])]

    def raise_if_any(self):
        if self._found:
            raise NetError(self.messages())


def did_you_mean(name, candidates):
    """' (did you mean 'x'?)' for the closest candidate, or ''."""
    match = difflib.get_close_matches(str(name), [str(c) for c in candidates], n=1)
    return f" (did you mean '{match[0]}'?)" if match else ""
