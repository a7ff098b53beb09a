/* Schema migrations embedded at build time from db/migrations/NNNN_*.sql. */
#ifndef PALP_DB_MIGRATIONS_H
#define PALP_DB_MIGRATIONS_H

typedef struct palp_db_migration {
  int version;      /* the schema version the script upgrades to */
  const char *name; /* file name, for error messages */
  const char *sql;
} palp_db_migration;

extern const palp_db_migration palp_db_migrations[];
extern const int palp_db_migration_count; /* = the current schema version */

#endif
