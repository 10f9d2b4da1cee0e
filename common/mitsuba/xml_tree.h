/* An XML file as a tree of elements, read by expat: what the Mitsuba
 * reader walks. Text content is dropped (Mitsuba keeps everything in
 * attributes); every element remembers its file and line for messages. */
#ifndef SG_XML_TREE_H
#define SG_XML_TREE_H

#include <stdbool.h>
#include <stddef.h>

#include "error.h"

typedef struct XmlDoc XmlDoc;

typedef struct XmlNode {
    char *tag;
    char **attrs; /* name, value, name, value, ... */
    size_t attr_count;
    struct XmlNode **children;
    size_t child_count, child_capacity;
    int line;
    bool substituted; /* "$name" replaced in its attribute values */
    const XmlDoc *doc;
} XmlNode;

struct XmlDoc {
    char path[4096];
    XmlNode *root;
    bool old_dialect; /* Mitsuba 0.x: camelCase property names */
};

/* Reads path into a tree; on_text (if given) sees the file's bytes first.
 * Fails with "path:line: cause" (expat's). */
XmlDoc *sg_xml_read(const char *path, void (*on_text)(void *context, const char *text, size_t size),
                    void *context, SgError *err);
void sg_xml_free(XmlDoc *doc);

/* The attribute's value, or NULL. */
const char *sg_xml_attr(const XmlNode *n, const char *name);

#endif
