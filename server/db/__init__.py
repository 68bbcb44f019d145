"""The database: SQLAlchemy 2 typed models (`models`), the engine with SQLite pragmas and the Alembic
upgrade at start-up (`engine`)."""
