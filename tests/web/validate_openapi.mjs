// Validates the server's OpenAPI description (/api/v1/openapi.json) against the OpenAPI 3.1
// schema with @seriousme/openapi-schema-validator (a maintained validator from the npm registry,
// installed into build/web-test by scripts/test.sh), and resolves every $ref in it.
// Run by tests/web/run_openapi.sh against a started server.
import { Validator } from '@seriousme/openapi-schema-validator';

const base = process.env.VOLSTYLE_URL + '/api/v1';
const doc = await (await fetch(base + '/openapi.json')).json();
const validator = new Validator();
const result = await validator.validate(doc);
if (!result.valid) {
  console.error('FAIL: the OpenAPI document does not match the OpenAPI ' + validator.version + ' schema:');
  console.error(JSON.stringify(result.errors, null, 1).slice(0, 4000));
  process.exit(1);
}
validator.resolveRefs();  // throws on a reference that does not resolve
const operations = Object.values(doc.paths).reduce((n, item) => n + Object.keys(item).length, 0);
console.log(`openapi ${validator.version}: valid, ${Object.keys(doc.paths).length} paths, ${operations} operations, ` +
            `${Object.keys(doc.components.schemas).length} schemas`);
