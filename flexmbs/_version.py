"""The version of flexmbs, in a module of its own so that any layer can import it without the
package facade (``flexmbs/__init__.py`` imports everything)."""

__version__ = "0.1.0"
