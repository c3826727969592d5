"""Walking a jaxpr's equations through the jaxprs nested in them (loops, branches, calls), for
tests that read what a program computes off its traced form."""


def sub_jaxprs(params):
    """The jaxprs among an equation's ``params`` (closed ones unwrapped)."""
    for value in params.values():
        for v in value if isinstance(value, (tuple, list)) else (value,):
            inner = getattr(v, "jaxpr", v)
            if hasattr(inner, "eqns"):
                yield inner


def all_equations(jaxpr):
    """Every equation of ``jaxpr`` and of the jaxprs nested in it, outer ones first."""
    for eqn in jaxpr.eqns:
        yield eqn
        for sub in sub_jaxprs(eqn.params):
            yield from all_equations(sub)
