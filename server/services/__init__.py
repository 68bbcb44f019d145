"""Services own the database work; routers call them (from FastAPI's thread pool: sync sessions)."""
