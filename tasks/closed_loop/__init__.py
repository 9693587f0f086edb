"""The mission core: closed-loop missions composed of parts, for one or more vehicles."""
