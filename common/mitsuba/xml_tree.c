/* XML files into trees through expat (see xml_tree.h). */
#include "xml_tree.h"

#include <expat.h>
#include <stdint.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "input_file.h"

/* Deeper nesting than any scene has: a guard against hostile files. */
#define MAX_XML_DEPTH 256

typedef struct Reader {
    XmlDoc *doc;
    XML_Parser parser;
    XmlNode *stack[MAX_XML_DEPTH];
    int depth;
    bool failed;
    char cause[256];
} Reader;

static void node_free(XmlNode *n)
{
    if (!n)
        return;
    for (size_t i = 0; i < n->child_count; i++)
        node_free(n->children[i]);
    for (size_t i = 0; i < 2 * n->attr_count; i++)
        free(n->attrs[i]);
    free(n->attrs);
    free(n->children);
    free(n->tag);
    free(n);
}

static void stop(Reader *r, const char *cause)
{
    if (!r->failed)
        snprintf(r->cause, sizeof r->cause, "%s", cause);
    r->failed = true;
    XML_StopParser(r->parser, XML_FALSE);
}

static void on_start(void *data, const XML_Char *tag, const XML_Char **attrs)
{
    Reader *r = data;
    if (r->failed)
        return;
    if (r->depth >= MAX_XML_DEPTH)
        return stop(r, "elements nested too deeply");
    XmlNode *n = calloc(1, sizeof *n);
    if (!n)
        return stop(r, "out of memory");
    n->line = (int)XML_GetCurrentLineNumber(r->parser);
    n->doc = r->doc;
    size_t count = 0;
    while (attrs[2 * count])
        count++;
    n->tag = strdup(tag);
    n->attrs = calloc(2 * count + 1, sizeof *n->attrs);
    bool ok = n->tag && n->attrs;
    for (size_t i = 0; ok && i < 2 * count; i++)
        ok = (n->attrs[i] = strdup(attrs[i])) != NULL;
    n->attr_count = count;
    XmlNode *parent = r->depth ? r->stack[r->depth - 1] : NULL;
    if (ok && parent && parent->child_count == parent->child_capacity) {
        size_t cap = parent->child_capacity ? 2 * parent->child_capacity : 4;
        XmlNode **grown = realloc(parent->children, cap * sizeof *grown);
        ok = grown != NULL;
        if (ok) {
            parent->children = grown;
            parent->child_capacity = cap;
        }
    }
    if (!ok) {
        node_free(n);
        return stop(r, "out of memory");
    }
    if (parent)
        parent->children[parent->child_count++] = n;
    else
        r->doc->root = n;
    r->stack[r->depth++] = n;
}

static void on_end(void *data, const XML_Char *tag)
{
    (void)tag;
    Reader *r = data;
    if (!r->failed && r->depth > 0)
        r->depth--;
}

XmlDoc *sg_xml_read(const char *path, void (*on_text)(void *context, const char *text, size_t size),
                    void *context, SgError *err)
{
    char *text = NULL;
    size_t size = 0;
    if (!sg_read_file(path, "scene", SG_LIMIT_PBRT_TEXT, &text, &size, err))
        return NULL;
    if (on_text)
        on_text(context, text, size);
    XmlDoc *doc = calloc(1, sizeof *doc);
    Reader r = {.doc = doc};
    if (doc)
        r.parser = XML_ParserCreate(NULL);
    if (!doc || !r.parser) {
        free(doc);
        free(text);
        sg_fail(err, "%s: out of memory", path);
        return NULL;
    }
    snprintf(doc->path, sizeof doc->path, "%s", path);
    XML_SetUserData(r.parser, &r);
    XML_SetElementHandler(r.parser, on_start, on_end);
    bool ok = size <= (size_t)INT32_MAX &&
              XML_Parse(r.parser, text, (int)size, XML_TRUE) == XML_STATUS_OK && !r.failed;
    if (!ok) {
        long line = (long)XML_GetCurrentLineNumber(r.parser);
        const char *cause = r.failed ? r.cause
                            : size > (size_t)INT32_MAX ? "file too large"
                                                       : XML_ErrorString(XML_GetErrorCode(r.parser));
        sg_fail(err, "%s:%ld: XML: %s", path, line, cause);
    } else if (!doc->root) {
        ok = sg_fail(err, "%s: no XML element", path);
    }
    XML_ParserFree(r.parser);
    free(text);
    if (!ok) {
        sg_xml_free(doc);
        return NULL;
    }
    return doc;
}

void sg_xml_free(XmlDoc *doc)
{
    if (!doc)
        return;
    node_free(doc->root);
    free(doc);
}

const char *sg_xml_attr(const XmlNode *n, const char *name)
{
    for (size_t i = 0; i < n->attr_count; i++)
        if (!strcmp(n->attrs[2 * i], name))
            return n->attrs[2 * i + 1];
    return NULL;
}
